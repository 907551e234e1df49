// AravisCamera's features (acquisition/aravis_features.cc): every write checked and read back,
// the state found saved (every trigger's own controls under each TriggerSelector entry, and the
// entry selected) and put back exactly, on Aravis's fake camera with a FLIR-style GenICam file
// (tests/acquisition/genicam/flir_style.xml). What the camera holds is read by another client.
#include "acquisition/aravis_camera.h"

#include <arv.h>
#include <gtest/gtest.h>

#include <string>
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

CameraSettings Triggered() {
  CameraSettings settings;
  settings.pixel_format = "Mono16";
  settings.trigger_source = "Line0";
  settings.width = 128;
  settings.height = 64;
  settings.exposure_us = 5000.0;
  return settings;
}

// A previous user's state, with each trigger's controls set differently: after Configure changed
// them, RestoreFound puts every one back, each under its own TriggerSelector entry. (The file's
// TriggerSelector itself is the client's own state, not the camera's: not checked here.)
TEST(AravisFeatures, RestoreFoundPutsBackEveryTriggersOwnControls) {
  testing::FakeCameraProcess fake("IRDFEA01", {"-g", Genicam("flir_style.xml")});
  {
    OtherClient previous_user;
    previous_user.Set("AcquisitionStart", "TriggerMode", "On");
    previous_user.Set("AcquisitionStart", "TriggerSource", "Line2");
    previous_user.Set("FrameStart", "TriggerActivation", "FallingEdge");
    previous_user.Set("FrameStart", "TriggerSource", "Software");
    previous_user.Set("", "ExposureAuto", "Continuous");
    previous_user.Set("", "PixelFormat", "Mono8");
    previous_user.Set("", "Width", "320");
  }
  {
    auto camera = AravisCamera::Open("127.0.0.1", "IRDFEA01");
    camera->Configure(Triggered());
    EXPECT_EQ(camera->ReadBackFeatures().at("PixelFormat"), "Mono16");
    EXPECT_EQ(camera->RestoreFound(), " The camera was put back as it was found.");
  }
  OtherClient check;
  EXPECT_EQ(check.Get("", "PixelFormat"), "Mono8");
  EXPECT_EQ(check.Get("", "Width"), "320");
  EXPECT_EQ(check.Get("", "ExposureAuto"), "Continuous");
  EXPECT_EQ(check.Get("AcquisitionStart", "TriggerMode"), "On");
  EXPECT_EQ(check.Get("AcquisitionStart", "TriggerSource"), "Line2");
  EXPECT_EQ(check.Get("FrameStart", "TriggerMode"), "Off");
  EXPECT_EQ(check.Get("FrameStart", "TriggerActivation"), "FallingEdge");
  EXPECT_EQ(check.Get("FrameStart", "TriggerSource"), "Software");
}

// An enumeration value the camera does not offer is refused listing what it offers; the camera
// is left as found.
TEST(AravisFeatures, AnEnumerationValueNotOfferedIsRefusedListingTheEntries) {
  testing::FakeCameraProcess fake("IRDFEA02", {"-g", Genicam("flir_style.xml")});
  auto camera = AravisCamera::Open("127.0.0.1", "IRDFEA02");
  CameraSettings settings = Triggered();
  settings.pixel_format = "Mono10";
  try {
    camera->Configure(settings);
    FAIL() << "PixelFormat Mono10 was accepted";
  } catch (const CameraError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("PixelFormat cannot be Mono10; it offers: Mono8, Mono12p, Mono16"),
              std::string::npos)
        << what;
    EXPECT_NE(what.find("IRDFEA02@127.0.0.1"), std::string::npos) << what;
  }
}

// Describe: an enumeration's value and entries under a selector entry (the selector put back
// after), a float's bounds from the GenICam file, and a feature the camera lacks.
TEST(AravisFeatures, DescribeReportsValuesEntriesAndBoundsAsTheCameraHasThem) {
  testing::FakeCameraProcess fake("IRDFEA03", {"-g", Genicam("flir_style.xml")});
  {
    OtherClient previous_user;
    previous_user.Set("AcquisitionStart", "TriggerSource", "Line2");
    previous_user.Set("", "TriggerSelector", "FrameStart");
  }
  auto camera = AravisCamera::Open("127.0.0.1", "IRDFEA03");
  const FeatureInfo source = camera->Describe("TriggerSource", "AcquisitionStart");
  EXPECT_TRUE(source.present);
  EXPECT_TRUE(source.writable);
  EXPECT_EQ(source.value, "Line2");
  EXPECT_EQ(source.entries, (std::vector<std::string>{"Line0", "Software", "Line2"}));
  EXPECT_EQ(camera->Describe("TriggerSelector").value, "FrameStart");
  const FeatureInfo exposure = camera->Describe("ExposureTime");
  ASSERT_TRUE(exposure.min.has_value() && exposure.max.has_value());
  EXPECT_DOUBLE_EQ(*exposure.min, 10.0);
  EXPECT_DOUBLE_EQ(*exposure.max, 1000000.0);
  const FeatureInfo gain = camera->Describe("Gain");
  EXPECT_DOUBLE_EQ(gain.max.value_or(-1.0), 47.0);
  const FeatureInfo none = camera->Describe("NoSuchFeature");
  EXPECT_FALSE(none.present);
  EXPECT_FALSE(none.writable);
  EXPECT_TRUE(none.entries.empty());
}

}  // namespace
}  // namespace irdist
