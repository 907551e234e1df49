// AravisCamera's frame trigger as the SFNC defines it (acquisition/aravis_trigger.cc), on Aravis's
// fake camera (arv-fake-gv-camera-0.8) with a FLIR-style GenICam file (tests/acquisition/genicam/
// flir_style.xml: TriggerSelector FrameStart, AcquisitionStart, FrameBurstStart; TriggerSource
// Line0, Software, Line2; TriggerActivation; TriggerOverlap; AcquisitionFrameRateEnable) and with
// its stock file. What irdist set is checked by another client reading the camera's features.
#include "acquisition/aravis_camera.h"

#include <arv.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "tests/acquisition/fake_camera_process.h"

namespace irdist {
namespace {

std::string Genicam(const char* file) {
  return std::string(IRDIST_SOURCE_DIR) + "/tests/acquisition/genicam/" + file;
}

// Another client's connection to the camera on 127.0.0.1: reads and writes features by name,
// under a TriggerSelector entry when given.
class OtherClient {
 public:
  OtherClient() {
    GError* error = nullptr;
    camera_ = arv_camera_new("127.0.0.1", &error);
    Check(error, "arv_camera_new");
  }
  ~OtherClient() {
    if (camera_ != nullptr) g_object_unref(camera_);
  }
  OtherClient(const OtherClient&) = delete;
  OtherClient& operator=(const OtherClient&) = delete;
  void Set(const std::string& selector, const char* feature, const char* value) {
    Select(selector);
    GError* error = nullptr;
    arv_gc_feature_node_set_value_from_string(Node(feature), value, &error);
    Check(error, feature);
  }
  std::string Get(const std::string& selector, const char* feature) {
    Select(selector);
    GError* error = nullptr;
    const char* value = arv_gc_feature_node_get_value_as_string(Node(feature), &error);
    Check(error, feature);
    return value == nullptr ? "" : value;
  }

 private:
  ArvGcFeatureNode* Node(const char* feature) {
    ArvGcNode* node = arv_device_get_feature(arv_camera_get_device(camera_), feature);
    EXPECT_NE(node, nullptr) << feature;
    return ARV_GC_FEATURE_NODE(node);
  }
  void Select(const std::string& selector) {
    if (selector.empty()) return;
    GError* error = nullptr;
    arv_camera_set_string(camera_, "TriggerSelector", selector.c_str(), &error);
    Check(error, "TriggerSelector");
  }
  static void Check(GError* error, const char* what) {
    if (error == nullptr) return;
    ADD_FAILURE() << what << ": " << error->message;
    g_error_free(error);
  }
  ArvCamera* camera_ = nullptr;
};

CameraSettings Settings(bool triggered) {
  CameraSettings settings;
  settings.pixel_format = "Mono8";
  settings.trigger_source = "Line0";
  settings.triggered = triggered;
  settings.width = 128;
  settings.height = 64;
  settings.exposure_us = 5000.0;
  return settings;
}

// One FLIR-style fake camera for the tests below; each sets the state it starts from.
class AravisTriggerTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    fake_ = new testing::FakeCameraProcess("IRDTRG01", {"-g", Genicam("flir_style.xml")});
  }
  static void TearDownTestSuite() {
    delete fake_;
    fake_ = nullptr;
  }
  static std::unique_ptr<AravisCamera> Open() {
    return AravisCamera::Open("127.0.0.1", "IRDTRG01");
  }
  static testing::FakeCameraProcess* fake_;
};
testing::FakeCameraProcess* AravisTriggerTest::fake_ = nullptr;

// A previous user left other triggers On, the exposure set by the trigger's width and a
// frame-rate limit: irdist triggers frames with FrameStart alone, on the rig's line and edge,
// accepted during readout, with timed exposures, continuous acquisition and no rate limit.
TEST_F(AravisTriggerTest, AHardwareTriggerIsFrameStartAloneOnTheRigsLineEdgeAndOverlap) {
  {
    OtherClient previous_user;
    previous_user.Set("AcquisitionStart", "TriggerMode", "On");
    previous_user.Set("FrameBurstStart", "TriggerMode", "On");
    previous_user.Set("", "ExposureMode", "TriggerWidth");
    previous_user.Set("", "AcquisitionMode", "SingleFrame");
    previous_user.Set("", "AcquisitionFrameRateEnable", "true");
  }
  CameraSettings settings = Settings(true);
  settings.trigger_activation = "FallingEdge";
  settings.trigger_in_readout = true;
  {
    auto camera = Open();
    camera->Configure(settings);
    EXPECT_EQ(camera->ReadBackFeatures().at("TriggerSelector"), "FrameStart");
  }
  OtherClient check;
  EXPECT_EQ(check.Get("FrameStart", "TriggerMode"), "On");
  EXPECT_EQ(check.Get("FrameStart", "TriggerSource"), "Line0");
  EXPECT_EQ(check.Get("FrameStart", "TriggerActivation"), "FallingEdge");
  EXPECT_EQ(check.Get("FrameStart", "TriggerOverlap"), "ReadOut");
  EXPECT_EQ(check.Get("AcquisitionStart", "TriggerMode"), "Off");
  EXPECT_EQ(check.Get("FrameBurstStart", "TriggerMode"), "Off");
  EXPECT_EQ(check.Get("", "ExposureMode"), "Timed");
  EXPECT_EQ(check.Get("", "AcquisitionMode"), "Continuous");
  EXPECT_EQ(check.Get("", "AcquisitionFrameRateEnable"), "false");
}

// Free-running with a rig rate: the frame trigger Off, the rate limit on at that rate.
TEST_F(AravisTriggerTest, FreeRunningTurnsTheFrameTriggerOffAndSetsTheRigsRate) {
  {
    OtherClient previous_user;
    previous_user.Set("FrameStart", "TriggerMode", "On");
  }
  CameraSettings settings = Settings(false);
  settings.frame_rate_hz = 12.5;
  {
    auto camera = Open();
    camera->Configure(settings);
  }
  OtherClient check;
  EXPECT_EQ(check.Get("FrameStart", "TriggerMode"), "Off");
  EXPECT_EQ(check.Get("", "AcquisitionFrameRateEnable"), "true");
  EXPECT_NEAR(std::stod(check.Get("", "AcquisitionFrameRate")), 12.5, 1e-6);
}

// Values the camera does not offer are refused, each naming the rig file's key to change.
TEST_F(AravisTriggerTest, ASourceOrEdgeTheCameraLacksIsRefusedNamingTheRigKey) {
  auto camera = Open();
  CameraSettings settings = Settings(true);
  settings.trigger_source = "Line1";
  try {
    camera->Configure(settings);
    ADD_FAILURE() << "TriggerSource Line1 was accepted";
  } catch (const CameraError& e) {
    EXPECT_NE(std::string(e.what()).find("camera.trigger_source"), std::string::npos) << e.what();
  }
  settings = Settings(true);
  settings.trigger_activation = "AnyEdge";
  try {
    camera->Configure(settings);
    ADD_FAILURE() << "TriggerActivation AnyEdge was accepted";
  } catch (const CameraError& e) {
    EXPECT_NE(std::string(e.what()).find("camera.trigger_activation"), std::string::npos)
        << e.what();
  }
}

// On the stock fake camera, free-running at 20 frames/s: frames 50 ms apart on its clock.
TEST(AravisTrigger, FreeRunningFramesComeAtTheRigsRate) {
  testing::FakeCameraProcess fake("IRDTRG04");
  auto camera = AravisCamera::Open("127.0.0.1", "IRDTRG04");
  CameraSettings settings = Settings(false);
  settings.trigger_source = "Software";
  settings.frame_rate_hz = 20.0;
  camera->Configure(settings);
  camera->StartStream();
  std::vector<std::pair<std::uint64_t, std::uint64_t>> ok_frames;  // frame id, timestamp (ns)
  for (int i = 0; i < 8; ++i) {
    const auto frame = camera->WaitFrame(std::chrono::milliseconds(2000));
    ASSERT_TRUE(frame.has_value()) << "frame " << i;
    if (frame->status == FrameStatus::kOk) {
      ok_frames.emplace_back(frame->frame_id, frame->timestamp_ns);
    }
  }
  camera->StopStream();
  ASSERT_GE(ok_frames.size(), 6u);
  std::vector<double> periods_ms;  // consecutive OK frames: time over the frame ids between them
  for (size_t i = 1; i < ok_frames.size(); ++i) {
    const auto ids = static_cast<std::int64_t>(ok_frames[i].first - ok_frames[i - 1].first);
    const auto ns = static_cast<std::int64_t>(ok_frames[i].second - ok_frames[i - 1].second);
    if (ids > 0) periods_ms.push_back(ns * 1e-6 / ids);  // ids <= 0: the 16-bit block id wrapped
  }
  ASSERT_FALSE(periods_ms.empty());
  std::nth_element(periods_ms.begin(), periods_ms.begin() + periods_ms.size() / 2,
                   periods_ms.end());
  // The median of the periods per frame id, as one damaged or missing frame between OK ones made
  // span / (n - 1) over the OK frames read ~58 ms.
  EXPECT_NEAR(periods_ms[periods_ms.size() / 2], 50.0, 5.0);
}

}  // namespace
}  // namespace irdist
