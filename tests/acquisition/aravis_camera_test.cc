// Tests of AravisCamera against Aravis's own fake GigE Vision camera on 127.0.0.1.
#include "acquisition/aravis_camera.h"
#include "acquisition/bracket.h"

#include <arv.h>
#include <gtest/gtest.h>

#include <set>
#include <string>

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

namespace irdist {
namespace {

// A failed setup puts back what it changed: the camera is as it was found.
TEST_F(AravisCameraTest, AFailedSetupPutsTheCameraBackAsItWasFound) {
  auto camera = AravisCamera::Open("127.0.0.1", kSerial);
  camera->Configure(FakeSettings(false));  // free-running, Mono8, 512 x 512
  const auto found = camera->ReadBackFeatures();
  CameraSettings bad = FakeSettings(true);
  bad.pixel_format = "Mono16";
  bad.width = 256;
  bad.trigger_source = "Line1";  // the stock fake camera has Line0 and Software only
  try {
    camera->Configure(bad);
    FAIL() << "expected CameraError";
  } catch (const CameraError& error) {
    EXPECT_NE(std::string(error.what()).find("put back as it was found"), std::string::npos)
        << error.what();
  }
  const auto after = camera->ReadBackFeatures();
  for (const char* feature : {"PixelFormat", "Width", "Height", "TriggerMode", "TriggerSource",
                              "TriggerSelector", "ExposureTimeAbs"}) {
    EXPECT_EQ(after.at(feature), found.at(feature)) << feature;
  }
}

// --- vendor-style GenICam files on Aravis's fake camera (tests/acquisition/genicam/) ------------

std::string Genicam(const char* file) {
  return std::string(IRDIST_SOURCE_DIR) + "/tests/acquisition/genicam/" + file;
}

// Another client's connection to the camera on 127.0.0.1 (a previous user, or a check of what
// irdist left): reads and writes features by name, under a TriggerSelector entry when given.
class OtherClient {
 public:
  OtherClient() {
    GError* error = nullptr;
    camera_ = arv_camera_new("127.0.0.1", &error);
    if (error != nullptr) {
      ADD_FAILURE() << error->message;
      g_error_free(error);
    }
  }
  ~OtherClient() {
    if (camera_ != nullptr) g_object_unref(camera_);
  }
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

CameraSettings Triggered(const char* pixel_format) {
  CameraSettings settings;
  settings.pixel_format = pixel_format;
  settings.trigger_source = "Software";
  settings.width = 256;
  settings.height = 128;
  settings.exposure_us = 5000.0;
  return settings;
}

// Three software-triggered frames arrive whole, with `bit_depth`.
void ExpectTriggeredFrames(AravisCamera& camera, int bit_depth) {
  camera.StartStream();
  for (int i = 0; i < 3; ++i) {
    camera.SoftwareTrigger();
    const auto frame = camera.WaitFrame(std::chrono::milliseconds(2000));
    ASSERT_TRUE(frame.has_value()) << "frame " << i;
    ASSERT_EQ(frame->status, FrameStatus::kOk) << FrameStatusName(frame->status);
    EXPECT_EQ(frame->image.cols, 256);
    EXPECT_EQ(frame->image.rows, 128);
    EXPECT_EQ(frame->bit_depth, bit_depth);
  }
  camera.StopStream();
}

// Basler-style: ExposureTimeAbs, GainRaw, no automatic features. A previous user left the
// AcquisitionStart trigger On, ExposureMode TriggerWidth and a frame-rate limit: irdist turns
// each back to its defined state and reads it back.
TEST(VendorCameras, BaslerStyleIsSetToTimedExposureAndFrameStartAlone) {
  testing::FakeCameraProcess fake("IRDBAS01", {"-g", Genicam("basler_style.xml")});
  {
    OtherClient previous_user;
    previous_user.Set("AcquisitionStart", "TriggerMode", "On");
    previous_user.Set("", "ExposureMode", "TriggerWidth");
    previous_user.Set("", "AcquisitionFrameRateEnable", "true");
  }
  auto camera = AravisCamera::Open("127.0.0.1", fake.serial());
  camera->Configure(Triggered("Mono12"));
  auto features = camera->ReadBackFeatures();
  EXPECT_EQ(features.at("ExposureMode"), "Timed");
  EXPECT_EQ(features.at("AcquisitionFrameRateEnable"), "false");
  EXPECT_EQ(features.at("TriggerSelector"), "FrameStart");
  EXPECT_EQ(features.at("TriggerMode"), "On");
  EXPECT_NEAR(std::stod(features.at("ExposureTimeAbs")), 5000.0, 1.0);
  EXPECT_EQ(features.count("ExposureAuto"), 0u);
  ExpectTriggeredFrames(*camera, 12);
  camera->Configure(Triggered("Mono12Packed"));
  ExpectTriggeredFrames(*camera, 12);
  camera.reset();
  OtherClient check;
  EXPECT_EQ(check.Get("AcquisitionStart", "TriggerMode"), "Off");
}

// Writes `text` (NUL-padded to 32 bytes) into the camera's memory at `address`, as another client.
void WriteCameraString(guint64 address, const std::string& text) {
  GError* error = nullptr;
  ArvCamera* other = arv_camera_new("127.0.0.1", &error);
  ASSERT_EQ(error, nullptr) << error->message;
  std::string padded = text;
  padded.resize(32, '\0');
  arv_device_write_memory(arv_camera_get_device(other), address, 32, padded.data(), &error);
  g_object_unref(other);
  ASSERT_EQ(error, nullptr) << error->message;
}

// A Basler ace's raw exposure timebase (ExposureTimeRaw x ExposureTimeBaseAbs, 20 us a step):
// the bounds irdist checks exposures against are in microseconds, those of ExposureTimeAbs,
// whatever Aravis's Basler quirk reports (the raw steps); an exposure in us is written and kept.
TEST(VendorCameras, BaslerRawTimebaseBoundsAreInMicroseconds) {
  testing::FakeCameraProcess fake("IRDBAS02", {"-g", Genicam("basler_raw_timebase.xml")});
  WriteCameraString(0x10c0, "Basler");
  WriteCameraString(0x10e0, "acA1300-60gm");
  auto camera = AravisCamera::Open("127.0.0.1", fake.serial());
  EXPECT_EQ(camera->Identity().vendor, "Basler");
  camera->Configure(Triggered("Mono12"));
  const auto [min_us, max_us] = camera->ExposureBoundsUs();
  EXPECT_NEAR(min_us, 40.0, 1e-6);
  EXPECT_NEAR(max_us, 1000000.0, 1e-3);
  EXPECT_NEAR(camera->SetExposureUs(300000.0), 300000.0, 1.0);  // above the raw maximum 50000
  const auto features = camera->ReadBackFeatures();
  EXPECT_NEAR(std::stod(features.at("ExposureTimeAbs")), 300000.0, 1.0);
  const std::string bounds = features.at("irdist.ExposureBounds");
  EXPECT_NE(bounds.find("(ExposureTimeAbs); Aravis reported [2, 50000]"), std::string::npos)
      << bounds;
}

// FLIR-style: ExposureAuto and GainAuto Continuous, GammaEnable and ExposureMode TriggerWidth at
// power-up, Mono12p and no Mono12. Mono12 is refused naming Mono12p; Mono12p streams with
// every automatic control off, gamma off, TriggerOverlap ReadOut and the other triggers Off.
TEST(VendorCameras, FlirStyleStreamsMono12pWithEveryAutomaticControlOff) {
  testing::FakeCameraProcess fake("IRDFLI01", {"-g", Genicam("flir_style.xml")});
  {
    OtherClient previous_user;
    previous_user.Set("FrameBurstStart", "TriggerMode", "On");
  }
  auto camera = AravisCamera::Open("127.0.0.1", fake.serial());
  try {
    camera->Configure(Triggered("Mono12"));
    FAIL() << "expected CameraError";
  } catch (const CameraError& error) {
    EXPECT_NE(std::string(error.what()).find("Mono12p"), std::string::npos) << error.what();
  }
  CameraSettings settings = Triggered("Mono12p");
  settings.trigger_in_readout = true;
  camera->Configure(settings);
  const auto features = camera->ReadBackFeatures();
  EXPECT_EQ(features.at("PixelFormat"), "Mono12p");
  EXPECT_EQ(features.at("ExposureAuto"), "Off");
  EXPECT_EQ(features.at("GainAuto"), "Off");
  EXPECT_EQ(features.at("GammaEnable"), "false");
  EXPECT_EQ(features.at("ExposureMode"), "Timed");
  EXPECT_EQ(features.at("AcquisitionFrameRateEnable"), "false");
  EXPECT_EQ(features.at("TriggerOverlap"), "ReadOut");
  EXPECT_EQ(camera->PayloadBytes(), 256 * 128 * 12 / 8);
  ExpectTriggeredFrames(*camera, 12);
  camera.reset();
  OtherClient check;
  EXPECT_EQ(check.Get("FrameBurstStart", "TriggerMode"), "Off");
  EXPECT_EQ(check.Get("AcquisitionStart", "TriggerMode"), "Off");
}

// A failed setup on the FLIR-style camera puts back its automatic controls, gamma and exposure
// mode as found.
TEST(VendorCameras, FlirStyleFailedSetupLeavesItAsFound) {
  testing::FakeCameraProcess fake("IRDFLI02", {"-g", Genicam("flir_style.xml")});
  auto camera = AravisCamera::Open("127.0.0.1", fake.serial());
  CameraSettings settings = Triggered("Mono12p");
  settings.trigger_source = "Line1";  // this camera's inputs are Line0 and Line2
  EXPECT_THROW(camera->Configure(settings), CameraError);
  camera.reset();
  OtherClient check;
  EXPECT_EQ(check.Get("", "ExposureAuto"), "Continuous");
  EXPECT_EQ(check.Get("", "GainAuto"), "Continuous");
  EXPECT_EQ(check.Get("", "GammaEnable"), "true");
  EXPECT_EQ(check.Get("", "ExposureMode"), "TriggerWidth");
  EXPECT_EQ(check.Get("", "PixelFormat"), "Mono8");
  EXPECT_EQ(check.Get("FrameStart", "TriggerMode"), "Off");
}

// A command done with the camera, however it ended (here while still streaming): with restore
// (camera.restore_after's default) every feature is put back as found; without, left as set.
TEST(VendorCameras, LeaveAsFoundStopsThenPutsBackOrLeavesAsSet) {
  testing::FakeCameraProcess fake("IRDFLI03", {"-g", Genicam("flir_style.xml")});
  for (const bool restore : {false, true}) {
    SCOPED_TRACE(restore ? "restore" : "leave");
    auto camera = AravisCamera::Open("127.0.0.1", fake.serial());
    camera->Configure(Triggered("Mono12p"));
    camera->StartStream();
    const std::string outcome = camera->LeaveAsFound(restore);
    EXPECT_FALSE(camera->streaming());
    EXPECT_EQ(outcome, restore ? "The camera was put back as it was found."
                               : "The camera is left as irdist set it (camera.restore_after: "
                                 "false in the rig file).");
    camera.reset();
    OtherClient check;
    EXPECT_EQ(check.Get("", "ExposureAuto"), restore ? "Continuous" : "Off");
    EXPECT_EQ(check.Get("FrameStart", "TriggerMode"), restore ? "Off" : "On");
    if (!restore) {  // the next round must find the camera as it was at the start
      check.Set("", "ExposureAuto", "Continuous");
      check.Set("FrameStart", "TriggerMode", "Off");
    }
  }
}

// GainAuto found holding no entry of its enumeration (enum_no_entry.xml): Configure sets it Off,
// and putting the camera back skips it by name, never writes it as "" nor asks for a power-cycle.
TEST(VendorCameras, AnEnumerationHoldingNoEntryIsSkippedAndNamedWhenPuttingBack) {
  testing::FakeCameraProcess fake("IRDENU01", {"-g", Genicam("enum_no_entry.xml")});
  auto camera = AravisCamera::Open("127.0.0.1", fake.serial());
  camera->Configure(Triggered("Mono12p"));
  const std::string outcome = camera->RestoreFound();
  EXPECT_NE(outcome.find("put back as it was found"), std::string::npos) << outcome;
  EXPECT_NE(outcome.find("Not put back: GainAuto"), std::string::npos) << outcome;
  EXPECT_EQ(outcome.find("power-cycle"), std::string::npos) << outcome;
  camera.reset();
  OtherClient check;
  EXPECT_EQ(check.Get("", "GainAuto"), "Off");
  EXPECT_EQ(check.Get("", "ExposureAuto"), "Continuous");  // the rest as found
  EXPECT_EQ(check.Get("", "GammaEnable"), "true");
}

// One trigger, no TriggerSelector (the SFNC allows it): configured and triggered as FrameStart.
TEST(VendorCameras, SingleTriggerWithoutSelectorIsTheFrameTrigger) {
  testing::FakeCameraProcess fake("IRDONE01", {"-g", Genicam("single_trigger.xml")});
  auto camera = AravisCamera::Open("127.0.0.1", fake.serial());
  camera->Configure(Triggered("Mono12"));
  const auto features = camera->ReadBackFeatures();
  EXPECT_EQ(features.count("TriggerSelector"), 0u);
  EXPECT_EQ(features.at("TriggerMode"), "On");
  EXPECT_EQ(features.at("TriggerSource"), "Software");
  ExpectTriggeredFrames(*camera, 12);
}

// No trigger at all: refused, naming what is missing, and left as found.
TEST(VendorCameras, MinimalCameraWithoutTriggerIsRefusedAndLeftAsFound) {
  testing::FakeCameraProcess fake("IRDMIN01", {"-g", Genicam("minimal.xml")});
  auto camera = AravisCamera::Open("127.0.0.1", fake.serial());
  try {
    camera->Configure(Triggered("Mono8"));
    FAIL() << "expected CameraError";
  } catch (const CameraError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("TriggerMode"), std::string::npos) << message;
    EXPECT_NE(message.find("TriggerSource"), std::string::npos) << message;
    EXPECT_NE(message.find("put back as it was found"), std::string::npos) << message;
  }
  camera.reset();
  OtherClient check;
  EXPECT_EQ(check.Get("", "Width"), "512");
}

// SFNC: ExposureStart starts one frame's exposure; with ExposureMode Timed (a previous user left
// TriggerWidth) and one exposure per trigger it is the camera's frame trigger.
TEST(VendorCameras, ExposureStartOnlyIsTheFrameTrigger) {
  testing::FakeCameraProcess fake("IRDEXS01", {"-g", Genicam("exposure_start_only.xml")});
  auto camera = AravisCamera::Open("127.0.0.1", fake.serial());
  camera->Configure(Triggered("Mono12"));
  const auto features = camera->ReadBackFeatures();
  EXPECT_EQ(features.at("TriggerSelector"), "ExposureStart");
  EXPECT_EQ(features.at("ExposureMode"), "Timed");
  EXPECT_EQ(features.at("TriggerMode"), "On");
  EXPECT_EQ(features.at("irdist.FrameTrigger"), "ExposureStart");
  ExpectTriggeredFrames(*camera, 12);
  // A bracket through it: every frame taken, each with the exposure asked for.
  BracketOptions options;
  options.exposures_us = {4000.0, 12000.0, 8000.0};
  options.trigger_source = "Software";
  BracketCapture capture(*camera, options);
  const BracketResult result = capture.Capture([&](int) { camera->SoftwareTrigger(); });
  camera->StopStream();
  ASSERT_TRUE(result.complete) << result.BriefReport();
  ASSERT_EQ(result.frames.size(), 3u);
  for (std::size_t i = 0; i < result.frames.size(); ++i) {
    EXPECT_NEAR(result.frames[i].actual_exposure_us, options.exposures_us[i], 1.0) << i;
  }
}

// A read-only TriggerSelector (derived from the exposure mode) with writable trigger controls is
// taken as it is: configured, triggered, never written.
TEST(VendorCameras, ReadOnlySelectorWithWritableControlsCaptures) {
  testing::FakeCameraProcess fake("IRDROS01", {"-g", Genicam("read_only_selector.xml")});
  auto camera = AravisCamera::Open("127.0.0.1", fake.serial());
  CameraSettings settings = Triggered("Mono12");
  settings.black_level = -1.0;  // its BlackLevel is locked (the next test)
  camera->Configure(settings);
  const auto features = camera->ReadBackFeatures();
  EXPECT_EQ(features.at("TriggerSelector"), "FrameStart");
  EXPECT_EQ(features.at("irdist.FrameTrigger"), "FrameStart");
  EXPECT_EQ(features.at("TriggerSource"), "Software");
  ExpectTriggeredFrames(*camera, 12);
}

// Aravis 0.8 writes a locked feature without a word: irdist checks first, and the message names
// the feature and the fix, never a source path; the camera is put back as found.
TEST(VendorCameras, ALockedFeatureIsRefusedByNameWithItsFix) {
  testing::FakeCameraProcess fake("IRDROS02", {"-g", Genicam("read_only_selector.xml")});
  auto camera = AravisCamera::Open("127.0.0.1", fake.serial());
  try {
    camera->Configure(Triggered("Mono12"));  // black_level 0 asks to write BlackLevel
    FAIL() << "expected CameraError";
  } catch (const CameraError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("BlackLevel is locked"), std::string::npos) << message;
    EXPECT_NE(message.find("camera.black_level to -1"), std::string::npos) << message;
    EXPECT_NE(message.find("put back as it was found"), std::string::npos) << message;
    EXPECT_EQ(message.find(".cc:"), std::string::npos) << message;
    EXPECT_EQ(message.find("powered, reachable"), std::string::npos) << message;
  }
  camera.reset();
  OtherClient check;
  EXPECT_EQ(check.Get("", "BlackLevel"), "4");
}

// An older camera's spellings and the pixel processing a previous user left on: each set neutral
// and recorded, the switches put back by a failed setup.
TEST(VendorCameras, OlderSpellingsAndPixelProcessingAreSetNeutralRecordedAndPutBack) {
  testing::FakeCameraProcess fake("IRDOLD01", {"-g", Genicam("older_spellings.xml")});
  auto camera = AravisCamera::Open("127.0.0.1", fake.serial());
  CameraSettings settings = Triggered("Mono12");
  settings.black_level = -1.0;  // no BlackLevel on this camera
  camera->Configure(settings);
  const auto features = camera->ReadBackFeatures();
  EXPECT_EQ(features.at("GammaEnabled"), "false");
  EXPECT_EQ(features.at("Gamma"), "1");
  EXPECT_EQ(features.at("LUTEnable"), "false");
  EXPECT_EQ(features.at("DigitalShift"), "0");
  EXPECT_EQ(features.at("BlackLevelEnabled"), "true");
  EXPECT_EQ(features.at("AcquisitionFrameRateEnabled"), "false");
  EXPECT_EQ(features.at("BinningHorizontalMode"), "Sum");  // stated, not written
  EXPECT_EQ(features.at("irdist.PixelPipeline"), "neutral");
  bool lut_found_on = false;
  for (const PixelFeatureState& state : camera->PixelPipeline()) {
    if (state.feature == "LUTEnable") lut_found_on = state.found == "true" && state.now == "false";
  }
  EXPECT_TRUE(lut_found_on);
  const std::string put_back = camera->RestoreFound();
  EXPECT_EQ(put_back, " The camera was put back as it was found.");
  camera.reset();
  OtherClient check;
  EXPECT_EQ(check.Get("", "LUTEnable"), "true");
  EXPECT_EQ(check.Get("", "GammaEnabled"), "true");
  EXPECT_EQ(check.Get("", "Gamma"), "0.45");
  EXPECT_EQ(check.Get("", "DigitalShift"), "2");
  EXPECT_EQ(check.Get("", "AcquisitionFrameRateEnabled"), "true");
}

// A raw colour mosaic in a Mono format is refused with the reason; a camera offering Bayer formats
// (Aravis's own fake camera) is named colour in recording.yaml's features.
TEST(VendorCameras, ARawMosaicIsRefusedAndAColourCameraNamed) {
  {
    testing::FakeCameraProcess fake("IRDRAW01", {"-g", Genicam("raw_mosaic.xml")});
    auto camera = AravisCamera::Open("127.0.0.1", fake.serial());
    try {
      camera->Configure(Triggered("Mono12"));
      FAIL() << "expected CameraError";
    } catch (const CameraError& error) {
      const std::string message = error.what();
      EXPECT_NE(message.find("raw colour mosaic (PixelColorFilter BayerRG)"), std::string::npos)
          << message;
      EXPECT_NE(message.find("Use a monochrome camera"), std::string::npos) << message;
    }
  }
  testing::FakeCameraProcess fake("IRDRAW02");
  auto camera = AravisCamera::Open("127.0.0.1", fake.serial());
  CameraSettings settings = Triggered("Mono16");
  camera->Configure(settings);
  const auto features = camera->ReadBackFeatures();
  EXPECT_EQ(features.at("irdist.Sensor").rfind("colour (Bayer pixel formats", 0), 0u)
      << features.at("irdist.Sensor");
}

}  // namespace
}  // namespace irdist
