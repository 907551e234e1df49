// AravisCamera's setup of what shapes a pixel (acquisition/aravis_setup.cc): automatic controls
// off, gain at its minimum and the rig's black level, gamma neutral (or the rig's), the region,
// and the exposure within the camera's own bounds, on Aravis's fake camera (a 2048 x 2048 sensor)
// with a FLIR-style GenICam file (tests/acquisition/genicam/flir_style.xml: Gain 0-47 dB,
// BlackLevel 0-10 %, GammaEnable and Gamma, ExposureTime 10 us - 1 s). What the camera holds is
// read by another client.
#include "acquisition/aravis_camera.h"

#include <arv.h>
#include <gtest/gtest.h>

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

// Another client's connection to the camera on 127.0.0.1: reads and writes features by name.
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
  void Set(const char* feature, const char* value) {
    GError* error = nullptr;
    arv_gc_feature_node_set_value_from_string(Node(feature), value, &error);
    Check(error, feature);
  }
  std::string Get(const char* feature) {
    GError* error = nullptr;
    const char* value = arv_gc_feature_node_get_value_as_string(Node(feature), &error);
    Check(error, feature);
    return value == nullptr ? "" : value;
  }
  double Number(const char* feature) { return std::stod(Get(feature)); }

 private:
  ArvGcFeatureNode* Node(const char* feature) {
    ArvGcNode* node = arv_device_get_feature(arv_camera_get_device(camera_), feature);
    EXPECT_NE(node, nullptr) << feature;
    return ARV_GC_FEATURE_NODE(node);
  }
  static void Check(GError* error, const char* what) {
    if (error == nullptr) return;
    ADD_FAILURE() << what << ": " << error->message;
    g_error_free(error);
  }
  ArvCamera* camera_ = nullptr;
};

CameraSettings Triggered() {
  CameraSettings settings;
  settings.pixel_format = "Mono16";
  settings.trigger_source = "Software";
  settings.width = 256;
  settings.height = 128;
  settings.exposure_us = 5000.0;
  return settings;
}

// One FLIR-style fake camera for the tests below; each sets what it needs before configuring.
class AravisSetupTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    fake_ = new testing::FakeCameraProcess("IRDSET01", {"-g", Genicam("flir_style.xml")});
  }
  static void TearDownTestSuite() {
    delete fake_;
    fake_ = nullptr;
  }
  static std::unique_ptr<AravisCamera> Open() {
    return AravisCamera::Open("127.0.0.1", "IRDSET01");
  }
  static testing::FakeCameraProcess* fake_;
};
testing::FakeCameraProcess* AravisSetupTest::fake_ = nullptr;

// A previous user left automatic exposure and gain on, 20 dB of gain, gamma on: irdist turns the
// automatic controls off, the gain to its minimum, the black level to the rig's, gamma off.
TEST_F(AravisSetupTest, AnalogControlsAreManualAtMinimumGainTheRigsBlackLevelAndLinear) {
  {
    OtherClient previous_user;
    previous_user.Set("ExposureAuto", "Continuous");
    previous_user.Set("GainAuto", "Continuous");
    previous_user.Set("Gain", "20");
    previous_user.Set("BlackLevel", "7.5");
    previous_user.Set("GammaEnable", "true");
  }
  CameraSettings settings = Triggered();
  settings.black_level = 2.5;
  std::vector<PixelFeatureState> pipeline;
  {
    auto camera = Open();
    camera->Configure(settings);
    pipeline = camera->PixelPipeline();
  }
  OtherClient check;
  EXPECT_EQ(check.Get("ExposureAuto"), "Off");
  EXPECT_EQ(check.Get("GainAuto"), "Off");
  EXPECT_NEAR(check.Number("Gain"), 0.0, 1e-6);
  EXPECT_NEAR(check.Number("BlackLevel"), 2.5, 1e-6);
  EXPECT_EQ(check.Get("GammaEnable"), "false");
  bool gamma_switch_seen = false;
  for (const PixelFeatureState& state : pipeline) {
    if (state.feature != "GammaEnable") continue;
    gamma_switch_seen = true;
    EXPECT_EQ(state.found, "true");
    EXPECT_EQ(state.now, "false");
    EXPECT_TRUE(state.neutral);
  }
  EXPECT_TRUE(gamma_switch_seen) << "GammaEnable not in the recorded pixel pipeline";
}

// A rig that asks for a gamma of 0.5 gets the curve switched on at that exponent.
TEST_F(AravisSetupTest, TheRigsOwnGammaIsSwitchedOnAtItsExponent) {
  CameraSettings settings = Triggered();
  settings.gamma = 0.5;
  Open()->Configure(settings);
  OtherClient check;
  EXPECT_EQ(check.Get("GammaEnable"), "true");
  EXPECT_NEAR(check.Number("Gamma"), 0.5, 1e-6);
}

// The region as asked (offsets included), 0 meaning the whole 2048 x 2048 sensor.
TEST_F(AravisSetupTest, TheRegionIsSetAsAskedAndTheWholeSensorByDefault) {
  CameraSettings settings = Triggered();
  settings.offset_x = 32;
  settings.offset_y = 16;
  {
    auto camera = Open();
    camera->Configure(settings);
    EXPECT_EQ(camera->PayloadBytes(), 256 * 128 * 2);
  }
  {
    OtherClient check;
    EXPECT_EQ(check.Get("Width"), "256");
    EXPECT_EQ(check.Get("Height"), "128");
    EXPECT_EQ(check.Get("OffsetX"), "32");
    EXPECT_EQ(check.Get("OffsetY"), "16");
  }
  settings = Triggered();
  settings.width = 0;
  settings.height = 0;
  auto camera = Open();
  camera->Configure(settings);
  const auto features = camera->ReadBackFeatures();
  EXPECT_EQ(features.at("Width"), "2048");
  EXPECT_EQ(features.at("Height"), "2048");
  EXPECT_EQ(features.at("OffsetX"), "0");
  EXPECT_EQ(camera->PayloadBytes(), 2048 * 2048 * 2);
}

// A region beyond the 2048 x 2048 sensor (too wide, or inside it only without its offset) is
// refused naming the sensor's bounds and the rig key, and nothing of it is written: the fake
// camera stores a width of 4096 and reads it back as set, so only the bounds can tell.
TEST_F(AravisSetupTest, ARegionBeyondTheSensorIsRefusedNamingItsBounds) {
  for (const auto& [width, offset_x] : {std::pair{4096, 0}, std::pair{256, 1900}}) {
    CameraSettings settings = Triggered();
    settings.width = width;
    settings.offset_x = offset_x;
    try {
      Open()->Configure(settings);
      ADD_FAILURE() << width << " px at " << offset_x << " was accepted";
    } catch (const CameraError& e) {
      EXPECT_NE(std::string(e.what()).find("2048"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("camera.roi_px"), std::string::npos) << e.what();
    }
    OtherClient check;
    EXPECT_NE(check.Get("Width"), std::to_string(width));
  }
}

// The exposure's bounds are the GenICam file's [10, 1000000] us; beyond them is refused before
// anything is written, naming the range.
TEST_F(AravisSetupTest, ExposuresOutsideTheCamerasBoundsAreRefusedNamingThem) {
  {
    auto camera = Open();
    camera->Configure(Triggered());
    EXPECT_EQ(camera->ExposureBoundsUs(), std::make_pair(10.0, 1000000.0));
    EXPECT_NEAR(camera->SetExposureUs(12345.0), 12345.0, 1.0);
    for (const double exposure_us : {5.0, 2e6}) {
      try {
        camera->SetExposureUs(exposure_us);
        ADD_FAILURE() << exposure_us << " us was accepted";
      } catch (const CameraError& e) {
        EXPECT_NE(std::string(e.what()).find("range [10, 1e+06] us"), std::string::npos)
            << e.what();
      }
    }
  }
  OtherClient check;
  EXPECT_NEAR(check.Number("ExposureTime"), 12345.0, 1.0);
}

// A rig that insists on exposure chunks, on a camera that declares none (the stock fake camera).
TEST(AravisSetup, ExposureChunksAskedOfACameraWithoutThemAreRefusedNamingTheRigKey) {
  testing::FakeCameraProcess fake("IRDSET05");
  auto camera = AravisCamera::Open("127.0.0.1", "IRDSET05");
  CameraSettings settings = Triggered();
  settings.pixel_format = "Mono8";
  settings.exposure_check = ExposureCheck::kChunk;
  try {
    camera->Configure(settings);
    FAIL() << "exposure_check: chunk was accepted";
  } catch (const CameraError& e) {
    EXPECT_NE(std::string(e.what()).find("camera.exposure_check: chunk"), std::string::npos)
        << e.what();
  }
  settings.exposure_check = ExposureCheck::kAuto;
  camera->Configure(settings);
  EXPECT_FALSE(camera->HasExposureChunks());
}

}  // namespace
}  // namespace irdist
