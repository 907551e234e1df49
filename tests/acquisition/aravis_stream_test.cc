// AravisCamera's stream (acquisition/aravis_stream.cc): the packet size, frames taken whole as
// 16-bit images one per trigger and stamped on arrival, the frames waiting flushed, the transfer
// counters; on Aravis's fake camera (arv-fake-gv-camera-0.8), and on the virtual rig's camera
// (sim/camera_server.h) for what the fake lacks: the GVCP capability register's PACKETRESEND bit
// (bootstrap 0x0934, bit 29 in the GigE Vision numbering) switched off, and ChunkExposureTime.
#include "acquisition/aravis_camera.h"

#include <gtest/gtest.h>

#include <chrono>
#include <memory>
#include <string>
#include <thread>

#include <opencv2/core.hpp>

#include "base/utc_time.h"
#include "sim/camera_server.h"
#include "tests/acquisition/fake_camera_process.h"
#include "tests/loopback_gvcp.h"

namespace irdist {
namespace {

constexpr char kSerial[] = "IRDSTR01";

CameraSettings Settings(bool triggered) {
  CameraSettings settings;
  settings.pixel_format = "Mono8";
  settings.trigger_source = "Software";
  settings.triggered = triggered;
  settings.width = 256;
  settings.height = 128;
  settings.exposure_us = 2000.0;
  return settings;
}

class AravisStreamTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { fake_ = new testing::FakeCameraProcess(kSerial); }
  static void TearDownTestSuite() {
    delete fake_;
    fake_ = nullptr;
  }
  static testing::FakeCameraProcess* fake_;
};
testing::FakeCameraProcess* AravisStreamTest::fake_ = nullptr;

// One frame a software trigger, none without: each whole, 256 x 128 as CV_16UC1 holding the
// Mono8 values (below 256), its id one more than the last, stamped when it was taken.
TEST_F(AravisStreamTest, EachTriggerGivesOneWholeFrameStampedOnArrival) {
  auto camera = AravisCamera::Open("127.0.0.1", kSerial);
  CameraSettings settings = Settings(true);
  settings.packet_size = 1500;
  camera->Configure(settings);
  EXPECT_EQ(camera->PacketSizeBytes(), 1500);
  EXPECT_EQ(camera->PayloadBytes(), 256 * 128);
  camera->StartStream();
  EXPECT_TRUE(camera->streaming());
  EXPECT_EQ(camera->warmup_discarded(), 1);
  std::uint64_t last_id = 0;
  for (int i = 0; i < 3; ++i) {
    const std::int64_t before_ns = UtcNowNs();
    camera->SoftwareTrigger();
    const auto frame = camera->WaitFrame(std::chrono::milliseconds(2000));
    const std::int64_t after_ns = UtcNowNs();
    ASSERT_TRUE(frame.has_value()) << "frame " << i;
    ASSERT_EQ(frame->status, FrameStatus::kOk) << FrameStatusName(frame->status);
    EXPECT_EQ(frame->image.type(), CV_16UC1);
    EXPECT_EQ(frame->image.cols, 256);
    EXPECT_EQ(frame->image.rows, 128);
    EXPECT_EQ(frame->bit_depth, 8);
    double max_value = 0.0;
    cv::minMaxLoc(frame->image, nullptr, &max_value);
    EXPECT_LE(max_value, 255.0);
    EXPECT_GT(max_value, 0.0) << "an empty image";
    if (last_id != 0) {
      EXPECT_EQ(frame->frame_id, last_id + 1);
    }
    last_id = frame->frame_id;
    EXPECT_GE(frame->host_time_ns, before_ns);
    EXPECT_LE(frame->host_time_ns, after_ns);
  }
  EXPECT_FALSE(camera->WaitFrame(std::chrono::milliseconds(200)).has_value());
  camera->StopStream();
  EXPECT_FALSE(camera->streaming());
  const TransferStats transfer = camera->Transfer();
  EXPECT_GE(transfer.completed_frames, 4u);  // the warm-up frame and the three
  EXPECT_EQ(transfer.failed_frames, 0u);
  EXPECT_EQ(transfer.missing_packets, 0u);
}

// Free-running at 25 frames/s, frames pile up in the stream's buffers: Flush returns them all.
TEST_F(AravisStreamTest, FlushReturnsEveryFrameWaitingInTheStream) {
  auto camera = AravisCamera::Open("127.0.0.1", kSerial);
  CameraSettings settings = Settings(false);
  settings.frame_rate_hz = 25.0;
  settings.warmup_frames = 0;
  camera->Configure(settings);
  camera->StartStream();
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  const int flushed = camera->Flush();
  camera->StopStream();
  EXPECT_GE(flushed, 4);  // 7 or 8 at 25 frames/s; fewer on a loaded host
  EXPECT_LE(flushed, settings.buffer_count);
}

// Before Configure there is no stream to start or wait on.
TEST_F(AravisStreamTest, StreamingBeforeConfigureIsRefused) {
  auto camera = AravisCamera::Open("127.0.0.1", kSerial);
  EXPECT_THROW(camera->StartStream(), Error);
  EXPECT_THROW(camera->WaitFrame(std::chrono::milliseconds(10)), Error);
  EXPECT_EQ(camera->Flush(), 0);
  EXPECT_FALSE(camera->streaming());
}

// The virtual rig's camera: its capability register says whether it resends, and its frames
// carry the exposure they were taken with.
TEST(AravisStreamVirtualCamera, ResendIsReadFromTheCapabilityRegisterAndChunksGiveTheExposure) {
  testing::LoopbackGvcpLock lock;
  sim::RigPhysics physics;
  physics.time_scale = 10.0;
  physics.camera.serial = "IRDSTR02";
  sim::World world(physics.time_scale);
  sim::CameraServer server(world, physics);
  server.Start();
  auto camera = AravisCamera::Open("127.0.0.1", "IRDSTR02");
  EXPECT_TRUE(camera->DeclaresPacketResend());
  server.SetPacketResend(false);
  EXPECT_FALSE(camera->DeclaresPacketResend());
  server.SetPacketResend(true);
  CameraSettings settings = Settings(true);
  settings.pixel_format = "Mono12";
  settings.exposure_us = 8000.0;
  camera->Configure(settings);
  ASSERT_TRUE(camera->HasExposureChunks());
  camera->StartStream();
  for (const double exposure_us : {8000.0, 3000.0}) {
    camera->WriteExposureUs(exposure_us);
    camera->SoftwareTrigger();
    const auto frame = camera->WaitFrame(std::chrono::milliseconds(3000));
    ASSERT_TRUE(frame.has_value());
    ASSERT_EQ(frame->status, FrameStatus::kOk) << FrameStatusName(frame->status);
    EXPECT_EQ(frame->bit_depth, 12);
    ASSERT_TRUE(frame->chunk_exposure_us.has_value());
    EXPECT_DOUBLE_EQ(*frame->chunk_exposure_us, exposure_us);
  }
  camera->StopStream();
}

}  // namespace
}  // namespace irdist
