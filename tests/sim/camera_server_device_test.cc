#include "sim/camera_server.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "base/check.h"
#include "sim/trajectory.h"
#include "tests/loopback_gvcp.h"

// The virtual camera as a device (sim/camera_server_device.cc): start and stop, the registers'
// power-up values, the triggers (Line1 pulses and TriggerSoftware, a queue of 4), the fault knobs'
// checks. The GVCP capability register (bootstrap 0x0934) declares WRITEMEM in bit 30 and
// PACKETRESEND in bit 29 (GigE Vision numbers bit 0 as the most significant): 1 << 1 and 1 << 2.

namespace irdist::sim {
namespace {

constexpr std::uint32_t kRegWidth = 0x100, kRegHeight = 0x104;  // sim/virtual_camera.xml
constexpr std::uint32_t kRegExposureUs = 0x120, kRegAcquisition = 0x124;
constexpr std::uint32_t kRegPixelFormat = 0x128;
constexpr std::uint32_t kRegOffsetX = 0x130, kRegOffsetY = 0x134;
constexpr std::uint32_t kRegTriggerMode = 0x300, kRegTriggerSoftware = 0x30c;
constexpr std::uint32_t kRegTriggerSource = 0x8000;  // 1 = Software, 2 = Line1
constexpr std::uint32_t kRegStreamPort = 0xd00, kRegPacketSize = 0xd04, kRegStreamAddress = 0xd18;
constexpr std::uint32_t kMono8 = 0x01080001, kMono12 = 0x01100005, kMono12p = 0x010c0047;
constexpr std::uint32_t kMono16 = 0x01100007;  // PFNC

std::uint16_t U16(const std::vector<std::uint8_t>& p, std::size_t at) {
  return static_cast<std::uint16_t>((p.at(at) << 8) | p.at(at + 1));
}
std::uint32_t U32(const std::vector<std::uint8_t>& p, std::size_t at) {
  return (static_cast<std::uint32_t>(U16(p, at)) << 16) | U16(p, at + 2);
}

int LoopbackSocket(std::uint16_t* port) {
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
std::vector<std::uint8_t> Receive(int fd, int timeout_ms) {
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

using CameraServerDeviceTest = CameraFixture<10>;
using CameraServerDeviceRealTimeTest = CameraFixture<1>;

constexpr std::uint32_t kRegSensorHeight = 0x118, kRegSensorWidth = 0x11c;
constexpr std::uint32_t kRegDeviceTemperature = 0x8008;  // milli-degrees Celsius, signed
constexpr std::uint32_t kRegGvcpCapability = 0x934;

// Power-up: the full sensor, Line1 as trigger source, the temperature in milli-degrees, and the
// capability register declaring WRITEMEM and PACKETRESEND; resend off clears only its own bit.
TEST_F(CameraServerDeviceTest, RegistersHoldTheirPowerUpValues) {
  EXPECT_EQ(Read(kRegWidth), 1280u);
  EXPECT_EQ(Read(kRegHeight), 1024u);
  EXPECT_EQ(Read(kRegSensorWidth), 1280u);
  EXPECT_EQ(Read(kRegSensorHeight), 1024u);
  EXPECT_EQ(Read(kRegTriggerSource), 2u);
  EXPECT_EQ(Read(kRegDeviceTemperature), 40000u);
  const std::uint32_t capability = Read(kRegGvcpCapability);
  EXPECT_EQ(capability & 0x6u, 0x6u);
  server_->SetPacketResend(false);
  EXPECT_EQ(Read(kRegGvcpCapability), capability & ~0x4u);
  server_->SetPacketResend(true);
  EXPECT_EQ(Read(kRegGvcpCapability), capability);
}

// Stop frees UDP 3956 at once, twice is harmless, and the camera starts again.
TEST_F(CameraServerDeviceTest, StopFreesThePortAndTheCameraStartsAgain) {
  EXPECT_TRUE(server_->running());
  EXPECT_FALSE(irdist::testing::LoopbackGvcpPortFree());
  server_->Stop();
  EXPECT_FALSE(server_->running());
  EXPECT_TRUE(irdist::testing::LoopbackGvcpPortFree());
  server_->Stop();
  EXPECT_FALSE(server_->running());
  server_->Start();
  EXPECT_TRUE(server_->running());
  EXPECT_EQ(Read(kRegWidth), 1280u);
  server_->Start();  // already running: nothing changes
  EXPECT_TRUE(server_->running());
}

TEST(CameraServerDevice, NamesItselfAsAravisNamesAFakeCamera) {
  RigPhysics physics;
  physics.camera.serial = "IRDDEV07";
  World world(1.0);
  CameraServer server(world, physics);
  EXPECT_EQ(server.serial(), "IRDDEV07");
  EXPECT_EQ(server.device_id(), "Aravis-Fake-IRDDEV07");
  EXPECT_EQ(server.address(), "127.0.0.1");
  EXPECT_FALSE(server.running());
}

TEST(CameraServerDevice, FaultKnobsOutsideTheirRangesAreRefused) {
  RigPhysics physics;
  World world(1.0);
  CameraServer server(world, physics);
  EXPECT_THROW(server.SetDropFrameRate(1.5), Error);
  EXPECT_THROW(server.SetDropFrameRate(-0.1), Error);
  EXPECT_THROW(server.SetLostPacketRatio(1.01), Error);
  EXPECT_THROW(server.SetExposureWriteDelayMs(-1.0), Error);
  EXPECT_THROW(server.SetExposureWriteDelayMs(std::nan("")), Error);
  EXPECT_NO_THROW(server.SetDropFrameRate(1.0));
  EXPECT_NO_THROW(server.SetLostPacketRatio(0.0));
  EXPECT_NO_THROW(server.SetExposureWriteDelayMs(0.0));
}

// A Line1 pulse starts a frame only with TriggerMode On, TriggerSource Line1 and acquisition on;
// with TriggerSource Software the line is not listened to, with acquisition off it is ignored.
TEST_F(CameraServerDeviceTest, Line1PulsesTriggerOnlyWhenLine1IsTheArmedSource) {
  Configure(32, 8, kMono8, 1500);  // TriggerSource Software
  world_.FireTrigger();
  EXPECT_TRUE(Receive(stream_, 300).empty());
  EXPECT_EQ(server_->LinePulsesAccepted(), 0u);
  Write(kRegTriggerSource, 2);  // Line1
  world_.FireTrigger();
  EXPECT_FALSE(Receive(stream_, 2000).empty());
  EXPECT_EQ(server_->LinePulsesAccepted(), 1u);
  while (!Receive(stream_, 300).empty()) {
  }
  Write(kRegAcquisition, 0);
  world_.FireTrigger();
  EXPECT_TRUE(Receive(stream_, 300).empty());
  EXPECT_EQ(server_->LinePulsesAccepted(), 1u);
  EXPECT_EQ(server_->Stats().triggers_ignored, 1u);
  EXPECT_EQ(server_->FramesExposed(), 1u);
}

// Triggers arriving while a 100 ms frame is exposed wait in a queue of 4; the rest are ignored.
// 1 + 4 frames in all.
TEST_F(CameraServerDeviceRealTimeTest, TriggersDuringAFrameQueueUpToFour) {
  Configure(16, 4, kMono8, 1500, 100000);
  Write(kRegTriggerSoftware, 1);
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  for (int i = 0; i < 6; ++i) Write(kRegTriggerSoftware, 1);
  Read(kRegWidth);  // served after the last trigger was offered (one control thread)
  const CameraServerStats stats = server_->Stats();
  EXPECT_EQ(stats.triggers_queued, 4u);
  EXPECT_EQ(stats.triggers_ignored, 2u);
  Write(kRegExposureUs, 1000);  // the queued frames latch it when they start
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(2);
  while (server_->FramesExposed() < 5 && std::chrono::steady_clock::now() < until) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  EXPECT_EQ(server_->FramesExposed(), 5u);
  const std::vector<FrameRecord> frames = server_->RecentFrames();
  ASSERT_EQ(frames.size(), 5u);
  EXPECT_EQ(frames[0].exposure_us, 100000.0);
  EXPECT_EQ(frames[4].exposure_us, 1000.0);
}

}  // namespace
}  // namespace irdist::sim
