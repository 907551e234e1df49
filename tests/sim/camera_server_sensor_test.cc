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

// The virtual camera's sensor (sim/camera_server_sensor.cc): a frame latches its settings when it
// starts, is exposed for its exposure, read out for the readout time and then sent, its payload
// the pixels in the format asked (PFNC: Mono8 1 byte, Mono16 2 bytes, Mono12p 12 bits packed
// LSB-first, two pixels in three bytes), and it records its truth. Spoken to in raw GVCP and
// received as raw GVSP, as in camera_server_gvsp_test.cc.

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

using CameraServerSensorTest = CameraFixture<10>;
using CameraServerSensorRealTimeTest = CameraFixture<1>;

// The payload bytes of one frame (the payload packets' data, leader and trailer left out).
std::vector<std::uint8_t> Payload(const std::vector<std::vector<std::uint8_t>>& packets) {
  std::vector<std::uint8_t> payload;
  for (std::size_t i = 1; i + 1 < packets.size(); ++i) {
    payload.insert(payload.end(), packets[i].begin() + 8, packets[i].end());
  }
  return payload;
}

// The exposure is the one set when the frame was triggered, not one written while it is exposed.
TEST_F(CameraServerSensorTest, TheExposureIsLatchedWhenTheFrameIsTriggered) {
  Configure(32, 8, kMono8, 1500, 2000);
  Write(kRegTriggerSoftware, 1);
  Write(kRegExposureUs, 9000);  // at once, while the first frame is exposed
  Write(kRegTriggerSoftware, 1);
  int trailers = 0;
  for (std::vector<std::uint8_t> p = Receive(stream_, 2000); !p.empty() && trailers < 2;
       p = trailers < 2 ? Receive(stream_, 2000) : p) {
    if (p.size() >= 8 && p[4] == 2) ++trailers;
  }
  ASSERT_EQ(trailers, 2);
  const std::vector<FrameRecord> frames = server_->RecentFrames();
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_EQ(frames[0].exposure_us, 2000.0);
  EXPECT_EQ(frames[1].exposure_us, 9000.0);
  EXPECT_EQ(frames[0].index, 1u);
  EXPECT_EQ(frames[1].index, 2u);
  EXPECT_EQ(frames[1].block_id, frames[0].block_id + 1);
}

// At time scale 1 a frame of 50 ms exposure and 12 ms readout leaves no sooner than 62 ms after
// its trigger.
TEST_F(CameraServerSensorRealTimeTest, AFrameLeavesAfterItsExposureAndReadout) {
  ASSERT_EQ(physics_.camera.readout_ms, 12.0);
  Configure(32, 8, kMono8, 1500, 50000);
  const auto start = std::chrono::steady_clock::now();
  const std::vector<std::vector<std::uint8_t>> packets = Frame();
  const double elapsed_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  ASSERT_FALSE(packets.empty());
  EXPECT_GE(elapsed_ms, 62.0 - 1.0);
  EXPECT_LT(elapsed_ms, 62.0 + 300.0);
}

// Bytes a frame: Mono8 1 a pixel, Mono16 2, Mono12p 12 bits (9 pixels: 108 bits in 14 bytes).
TEST_F(CameraServerSensorTest, ThePayloadHoldsEachPixelInItsFormatsSize) {
  struct Case {
    std::uint32_t format;
    int width, height;
    std::size_t bytes;
    const char* name;
  };
  const Case cases[] = {{kMono8, 30, 10, 300, "Mono8"},
                        {kMono16, 30, 10, 600, "Mono16"},
                        {kMono12p, 30, 10, 450, "Mono12p"},
                        {kMono12p, 3, 3, 14, "Mono12p"},
                        {kMono12, 30, 10, 600, "Mono12"}};
  for (const Case& c : cases) {
    Configure(c.width, c.height, c.format, 1500);
    const std::vector<std::vector<std::uint8_t>> packets = Frame();
    ASSERT_GE(packets.size(), 3u) << c.name;
    EXPECT_EQ(Payload(packets).size(), c.bytes) << c.name << " " << c.width << "x" << c.height;
    EXPECT_EQ(server_->RecentFrames().back().format, c.name);
  }
}

double Median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

// A dark corner in Mono12 and in Mono12p, the black level raised to 200 DN. Unpacked LSB-first
// (pixel a's low 8 bits, then a's high 4 bits in the low nibble with b's low 4 bits above, then
// b's high 8 bits), the packed frame's gray levels are the Mono12 frame's, all within 12 bits.
TEST_F(CameraServerSensorTest, Mono12pPacksTwelveBitPixelsLsbFirst) {
  world_.SetCurrent(0);
  Configure(64, 16, kMono12, 1500);
  Write(kRegOffsetX, 0);
  Write(kRegOffsetY, 0);
  Write(0x800c, 200);  // BlackLevel: gray levels above 255, their low nibbles not all 0
  const std::vector<std::uint8_t> wide = Payload(Frame());
  ASSERT_EQ(wide.size(), 64u * 16u * 2u);
  std::vector<double> mono12;
  for (std::size_t i = 0; i < wide.size(); i += 2) mono12.push_back(wide[i] | (wide[i + 1] << 8));
  Write(kRegPixelFormat, kMono12p);
  const std::vector<std::uint8_t> packed = Payload(Frame());
  ASSERT_EQ(packed.size(), 64u * 16u * 3u / 2u);
  std::vector<double> mono12p;
  for (std::size_t i = 0; i + 2 < packed.size(); i += 3) {
    mono12p.push_back(packed[i] | ((packed[i + 1] & 0x0f) << 8));
    mono12p.push_back((packed[i + 1] >> 4) | (packed[i + 2] << 4));
  }
  const double dark = Median(mono12);
  EXPECT_GT(dark, 200.0) << "the black level was not applied to the Mono12 frame";
  EXPECT_NEAR(Median(mono12p), dark, 3.0);
  EXPECT_LE(*std::max_element(mono12p.begin(), mono12p.end()), 4095.0);
  EXPECT_LE(*std::max_element(mono12.begin(), mono12.end()), 4095.0);
}

// Without a station profile the truth is the World's pose at the exposure's start; the
// timestamp is the start on the world's clock in ns.
TEST_F(CameraServerSensorTest, AFrameRecordsItsPoseCurrentAndStartTime) {
  const double before_s = world_.clock().Now();
  Configure(32, 8, kMono8, 1500, 4000);
  ASSERT_FALSE(Frame().empty());
  const double after_s = world_.clock().Now();
  const std::vector<FrameRecord> frames = server_->RecentFrames();
  ASSERT_EQ(frames.size(), 1u);
  const FrameRecord& f = frames[0];
  EXPECT_FALSE(f.truth_from_trajectory);
  EXPECT_EQ(f.slide_mm, 2000.0);
  EXPECT_EQ(f.pan_deg, 0.0);
  EXPECT_EQ(f.bias_ma, 500.0);
  EXPECT_FALSE(f.moving);
  EXPECT_FALSE(f.dropped);
  EXPECT_EQ(f.exposure_us, 4000.0);
  EXPECT_GE(f.sim_time_s, before_s);
  EXPECT_LE(f.sim_time_s + 4000e-6, after_s);
  EXPECT_NEAR(static_cast<double>(f.timestamp_ns), f.sim_time_s * 1e9, 1.0);
}

// A dropped frame is exposed and recorded, but never sent.
TEST_F(CameraServerSensorTest, ADroppedFrameIsRecordedButNeverSent) {
  server_->SetDropFrameRate(1.0);
  Configure(32, 8, kMono8, 1500);
  EXPECT_TRUE(Frame(500).empty());
  EXPECT_EQ(server_->FramesExposed(), 1u);
  EXPECT_EQ(server_->FramesDropped(), 1u);
  ASSERT_EQ(server_->RecentFrames().size(), 1u);
  EXPECT_TRUE(server_->RecentFrames()[0].dropped);
}

}  // namespace
}  // namespace irdist::sim
