#pragma once
// The virtual camera's tests over raw GVCP/GVSP on loopback (tests/sim/camera_server_*_test.cc):
// its registers (sim/virtual_camera.xml), big-endian field readers, UDP sockets, and a fixture
// that starts a CameraServer at a time scale, writes and reads registers and collects frames.

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <memory>
#include <vector>

#include "sim/camera_server.h"
#include "tests/loopback_gvcp.h"

namespace irdist::sim {

inline constexpr std::uint32_t kRegWidth = 0x100, kRegHeight = 0x104;  // sim/virtual_camera.xml
inline constexpr std::uint32_t kRegExposureUs = 0x120, kRegAcquisition = 0x124;
inline constexpr std::uint32_t kRegPixelFormat = 0x128;
inline constexpr std::uint32_t kRegOffsetX = 0x130, kRegOffsetY = 0x134;
inline constexpr std::uint32_t kRegTriggerMode = 0x300, kRegTriggerSoftware = 0x30c;
inline constexpr std::uint32_t kRegTriggerSource = 0x8000;  // 1 = Software, 2 = Line1
inline constexpr std::uint32_t kRegChunkModeActive = 0x8010, kRegChunkEnableExposure = 0x8018;
inline constexpr std::uint32_t kRegStreamPort = 0xd00, kRegPacketSize = 0xd04, kRegStreamAddress = 0xd18;
inline constexpr std::uint32_t kMono8 = 0x01080001, kMono12 = 0x01100005, kMono12p = 0x010c0047;
inline constexpr std::uint32_t kMono16 = 0x01100007;  // PFNC

inline std::uint16_t U16(const std::vector<std::uint8_t>& p, std::size_t at) {
  return static_cast<std::uint16_t>((p.at(at) << 8) | p.at(at + 1));
}
inline std::uint32_t U32(const std::vector<std::uint8_t>& p, std::size_t at) {
  return (static_cast<std::uint32_t>(U16(p, at)) << 16) | U16(p, at + 2);
}

inline int LoopbackSocket(std::uint16_t* port) {
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in local{};
  local.sin_family = AF_INET;
  local.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  EXPECT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&local), sizeof(local)), 0);
  socklen_t size = sizeof(local);
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&local), &size);
  if (port != nullptr) *port = ntohs(local.sin_port);
  return fd;
}

// The next datagram on `fd`, or {} after `timeout_ms`.
inline std::vector<std::uint8_t> Receive(int fd, int timeout_ms) {
  pollfd wait{fd, POLLIN, 0};
  if (::poll(&wait, 1, timeout_ms) != 1) return {};
  std::vector<std::uint8_t> packet(9000);
  const ssize_t got = ::recv(fd, packet.data(), packet.size(), 0);
  packet.resize(got > 0 ? static_cast<std::size_t>(got) : 0);
  return packet;
}

template <int kTimeScale>
class CameraFixture : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(irdist::testing::WaitForLoopbackGvcpPort(std::chrono::seconds(120)))
        << "127.0.0.1:3956 stayed busy: another fake camera is running";
    physics_.time_scale = kTimeScale;
    server_ = std::make_unique<CameraServer>(world_, physics_);
    server_->Start();
    control_ = LoopbackSocket(nullptr);
    stream_ = LoopbackSocket(&stream_port_);
    world_.SetPose(2000, 0, 0, false);
    world_.SetCurrent(500);
  }
  void TearDown() override {
    server_.reset();
    ::close(control_);
    ::close(stream_);
  }

  void Write(std::uint32_t address, std::uint32_t value) {
    const std::uint8_t packet[] = {
        0x42, 0x01, 0x00, 0x82, 0x00, 0x08, 0x00, ++id_,
        static_cast<std::uint8_t>(address >> 24), static_cast<std::uint8_t>(address >> 16),
        static_cast<std::uint8_t>(address >> 8), static_cast<std::uint8_t>(address),
        static_cast<std::uint8_t>(value >> 24), static_cast<std::uint8_t>(value >> 16),
        static_cast<std::uint8_t>(value >> 8), static_cast<std::uint8_t>(value)};
    SendControl(packet, sizeof(packet));
    const std::vector<std::uint8_t> ack = Receive(control_, 2000);
    ASSERT_EQ(ack.size(), 12u) << "no WRITEREG_ACK for 0x" << std::hex << address;
    ASSERT_EQ(U16(ack, 0), 0) << "write of 0x" << std::hex << address << " refused";
  }
  std::uint32_t Read(std::uint32_t address) {
    const std::uint8_t packet[] = {
        0x42, 0x01, 0x00, 0x80, 0x00, 0x04, 0x00, ++id_,
        static_cast<std::uint8_t>(address >> 24), static_cast<std::uint8_t>(address >> 16),
        static_cast<std::uint8_t>(address >> 8), static_cast<std::uint8_t>(address)};
    SendControl(packet, sizeof(packet));
    const std::vector<std::uint8_t> ack = Receive(control_, 2000);
    EXPECT_EQ(ack.size(), 12u) << "no READREG_ACK for 0x" << std::hex << address;
    return ack.size() == 12 ? U32(ack, 8) : 0xdeadbeef;
  }
  void SendControl(const std::uint8_t* packet, std::size_t size) {
    sockaddr_in camera{};
    camera.sin_family = AF_INET;
    camera.sin_port = htons(3956);
    camera.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ASSERT_EQ(::sendto(control_, packet, size, 0, reinterpret_cast<sockaddr*>(&camera),
                       sizeof(camera)),
              static_cast<ssize_t>(size));
  }

  // Region, format and stream destination; software-triggered frames of `exposure_us`.
  void Configure(int width, int height, std::uint32_t format, std::uint32_t packet_size,
                 std::uint32_t exposure_us = 1000) {
    Write(kRegWidth, static_cast<std::uint32_t>(width));
    Write(kRegHeight, static_cast<std::uint32_t>(height));
    Write(kRegOffsetX, 600);
    Write(kRegOffsetY, 480);
    Write(kRegPixelFormat, format);
    Write(kRegExposureUs, exposure_us);
    Write(kRegStreamAddress, 0x7f000001);
    Write(kRegStreamPort, stream_port_);
    Write(kRegPacketSize, packet_size);
    Write(kRegTriggerMode, 1);
    Write(kRegTriggerSource, 1);
    Write(kRegAcquisition, 1);
  }
  // One triggered frame's packets, up to the trailer (or what came before a silence).
  std::vector<std::vector<std::uint8_t>> Frame(int silence_ms = 2000) {
    Write(kRegTriggerSoftware, 1);
    std::vector<std::vector<std::uint8_t>> packets;
    while (true) {
      std::vector<std::uint8_t> packet = Receive(stream_, silence_ms);
      if (packet.empty()) break;
      packets.push_back(packet);
      if (packet.size() >= 8 && packet[4] == 2) break;  // trailer
    }
    return packets;
  }

  RigPhysics physics_;
  World world_{static_cast<double>(kTimeScale)};
  std::unique_ptr<CameraServer> server_;
  int control_ = -1, stream_ = -1;
  std::uint16_t stream_port_ = 0;
  std::uint8_t id_ = 0;
};

}  // namespace irdist::sim
