// Tests of AravisCamera against Aravis's own fake GigE Vision camera on 127.0.0.1.
#include "acquisition/aravis_camera.h"

#include <gtest/gtest.h>

#include <set>

#include "tests/acquisition/fake_camera_process.h"

namespace irdist {
namespace {

using testing::FakeCameraProcess;
constexpr char kSerial[] = "IRDACQ01";

CameraSettings FakeSettings(bool triggered) {
  CameraSettings settings;
  settings.pixel_format = "Mono8";
  settings.trigger_source = "Software";
  settings.triggered = triggered;
  settings.exposure_us = 10000.0;
  settings.width = 512;  // 0 would mean the whole 2048 x 2048 sensor
  settings.height = 512;
  return settings;
}

TEST(CameraSettings, DefaultsAreValid) {
  std::string why;
  EXPECT_TRUE(CameraSettings().IsValid(&why)) << why;
  CameraSettings bad;
  bad.pixel_format = "RGB8";
  EXPECT_FALSE(bad.IsValid(&why));
  EXPECT_NE(why.find("pixel_format"), std::string::npos);
}

TEST(FrameStatus, EveryStatusHasAName) {
  EXPECT_STREQ(FrameStatusName(FrameStatus::kOk), "ok");
  EXPECT_STREQ(FrameStatusName(FrameStatus::kUnknown), "unknown");
  EXPECT_STREQ(FrameStatusName(FrameStatus::kTimeout), "timeout");
}

class AravisCameraTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { fake_ = new FakeCameraProcess(kSerial); }
  static void TearDownTestSuite() {
    delete fake_;
    fake_ = nullptr;
  }
  static FakeCameraProcess* fake_;
};
FakeCameraProcess* AravisCameraTest::fake_ = nullptr;

TEST_F(AravisCameraTest, OpensByAddressAndReadsIdentity) {
  auto by_ip = AravisCamera::Open("127.0.0.1", kSerial);
  const CameraIdentity identity = by_ip->Identity();
  EXPECT_EQ(identity.serial, kSerial);
  EXPECT_EQ(identity.vendor, "Aravis");
  EXPECT_EQ(identity.model, "Fake");
  EXPECT_FALSE(identity.firmware.empty());
  EXPECT_EQ(identity.address, "127.0.0.1");
  by_ip.reset();

}

// Names are resolved against a device list; the list itself comes from discovery, which
// broadcasts on every interface, so the tests hand in a list instead of discovering.
TEST(ResolveCamera, FindsByIdOrSerialAndListsWhatItFoundOtherwise) {
  const std::vector<DeviceInfo> devices = {
      {"Basler-acA1300-21714", "Basler", "acA1300", "21714", "192.0.2.40", "GigEVision"},
      {"Aravis-Fake-GV01", "Aravis", "Fake", "GV01", "127.0.0.1", "GigEVision"}};
  EXPECT_EQ(ResolveCamera("Aravis-Fake-GV01", devices).address, "127.0.0.1");
  EXPECT_EQ(ResolveCamera("21714", devices).id, "Basler-acA1300-21714");
  try {
    ResolveCamera("no-such-camera-xyz", devices);
    FAIL() << "expected CameraError";
  } catch (const CameraError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("no-such-camera-xyz"), std::string::npos) << message;
    EXPECT_NE(message.find("Aravis-Fake-GV01 (127.0.0.1)"), std::string::npos) << message;
  }
  EXPECT_THROW(ResolveCamera("GV01x", {}), CameraError);
}

TEST_F(AravisCameraTest, WrongSerialOrUnknownNameIsACameraError) {
  try {
    AravisCamera::Open("127.0.0.1", "NOT-THIS-ONE");
    FAIL() << "expected CameraError";
  } catch (const CameraError& error) {
    EXPECT_NE(std::string(error.what()).find("NOT-THIS-ONE"), std::string::npos);
  }
}

TEST_F(AravisCameraTest, MissingPixelFormatOrTriggerSourceIsAClearCameraError) {
  auto camera = AravisCamera::Open("127.0.0.1", kSerial);
  CameraSettings settings = FakeSettings(true);
  settings.pixel_format = "Mono12";  // the fake camera offers Mono8 and Mono16 only
  try {
    camera->Configure(settings);
    FAIL() << "expected CameraError";
  } catch (const CameraError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("PixelFormat"), std::string::npos) << message;
    EXPECT_NE(message.find("Mono16"), std::string::npos) << message;  // lists what it offers
  }
  settings = FakeSettings(true);
  settings.trigger_source = "Line1";  // the stock fake camera has Line0 and Software
  EXPECT_THROW(camera->Configure(settings), CameraError);
}

TEST_F(AravisCameraTest, ConfigureReadsBackAndRecordsFeatures) {
  auto camera = AravisCamera::Open("127.0.0.1", kSerial);
  CameraSettings settings = FakeSettings(true);
  settings.pixel_format = "Mono16";
  settings.width = 256;
  settings.height = 128;
  settings.offset_x = 16;
  camera->Configure(settings);
  const auto features = camera->ReadBackFeatures();
  EXPECT_EQ(features.at("PixelFormat"), "Mono16");
  EXPECT_EQ(features.at("TriggerMode"), "On");
  EXPECT_EQ(features.at("TriggerSource"), "Software");
  EXPECT_EQ(features.at("TriggerSelector"), "FrameStart");
  EXPECT_EQ(features.at("Width"), "256");
  EXPECT_EQ(features.at("Height"), "128");
  EXPECT_EQ(features.at("OffsetX"), "16");
  EXPECT_EQ(features.at("GainAuto"), "Off");
  EXPECT_EQ(camera->PayloadBytes(), 256 * 128 * 2);
  EXPECT_NEAR(camera->SetExposureUs(20000.0), 20000.0, 1.0);
  EXPECT_NEAR(camera->ExposureUs(), 20000.0, 1.0);
  EXPECT_THROW(camera->SetExposureUs(1e12), CameraError);  // outside the camera's range
}

TEST_F(AravisCameraTest, FreeRuns100FramesAndSoftwareTriggers20WithNoneLost) {
  auto camera = AravisCamera::Open("127.0.0.1", kSerial);
  camera->Configure(FakeSettings(false));
  camera->StartStream();
  int ok = 0;
  int failed = 0;
  std::uint64_t last_id = 0;
  for (int i = 0; i < 100; ++i) {
    auto frame = camera->WaitFrame(std::chrono::milliseconds(2000));
    ASSERT_TRUE(frame.has_value()) << "no frame " << i;
    if (frame->status != FrameStatus::kOk) {
      ++failed;
      ADD_FAILURE() << "free-run frame " << i << ": " << FrameStatusName(frame->status);
      continue;
    }
    ++ok;
    EXPECT_EQ(frame->image.type(), CV_16UC1);
    EXPECT_EQ(frame->image.cols, 512);
    if (last_id != 0) {
      EXPECT_EQ(frame->frame_id, last_id + 1);
    }
    last_id = frame->frame_id;
  }
  camera->StopStream();
  EXPECT_EQ(ok, 100);
  EXPECT_EQ(failed, 0);

  camera->Configure(FakeSettings(true));
  camera->StartStream();
  std::set<std::uint64_t> ids;
  std::uint64_t last_timestamp = 0;
  for (int i = 0; i < 20; ++i) {
    camera->SoftwareTrigger();
    auto frame = camera->WaitFrame(std::chrono::milliseconds(2000));
    ASSERT_TRUE(frame.has_value()) << "triggered frame " << i << " lost";
    ASSERT_EQ(frame->status, FrameStatus::kOk) << FrameStatusName(frame->status);
    EXPECT_TRUE(ids.insert(frame->frame_id).second);
    EXPECT_GT(frame->timestamp_ns, last_timestamp);
    last_timestamp = frame->timestamp_ns;
  }
  // No trigger, no frame.
  EXPECT_FALSE(camera->WaitFrame(std::chrono::milliseconds(200)).has_value());
  camera->StopStream();
  EXPECT_EQ(ids.size(), 20u);
  const auto stats = camera->StreamStatistics();
  // Only the warm-up frames (discarded by StartStream, before the 20) may have failed.
  EXPECT_LE(stats.at("n_failures"), static_cast<std::uint64_t>(camera->warmup_discarded()));
  EXPECT_GE(stats.at("n_completed_buffers"), 20u);
}

}  // namespace
}  // namespace irdist
