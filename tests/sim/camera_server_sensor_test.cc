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
#include "tests/sim/camera_server_fixture.h"

// The virtual camera's sensor (sim/camera_server_sensor.cc): a frame latches its settings when it
// starts, is exposed for its exposure, read out for the readout time and then sent, its payload
// the pixels in the format asked (PFNC: Mono8 1 byte, Mono16 2 bytes, Mono12p 12 bits packed
// LSB-first, two pixels in three bytes), and it records its truth. Spoken to in raw GVCP and
// received as raw GVSP, as in camera_server_gvsp_test.cc.

namespace irdist::sim {
namespace {

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
