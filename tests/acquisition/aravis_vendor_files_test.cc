// Real vendors' GenICam files (Basler acA1300-60gm, FLIR Blackfly S BFS-PGE-19S4M, Allied Vision
// Mako G-125B, Teledyne DALSA Shad-o-Box) served by Aravis's fake camera, their register addresses
// moved into its memory (tests/acquisition/genicam/vendors/README.md): irdist's Configure,
// camera-test, a bracket and the camera put back as found, per file.
#include <arv.h>
#include <gtest/gtest.h>

#include <map>
#include <set>
#include <string>
#include <vector>

#include "acquisition/aravis_camera.h"
#include "acquisition/bracket.h"
#include "app/devices/camera_test.h"
#include "tests/acquisition/vendor_camera.h"

namespace irdist {
namespace {

using testing::OtherClient;

// One vendor file and what irdist must make of it on the fake camera.
struct Vendor {
  const char* fixture;
  const char* serial;
  const char* pixel_format;        // the one irdist is asked for
  double min_us, max_us;           // the exposure's bounds in microseconds
  std::set<std::string> cannot;    // camera-test rows the fake camera cannot pass
  bool frames;                     // whether the fake camera frames its software triggers
  const char* bounds_note = "";    // in irdist.ExposureBounds: where the bounds came from
};

// What the fake camera cannot do: GVCP packet resend (every file); an exposure that changes the
// image (linearity: its test pattern ignores the vendor's exposure register; FLIR's integer
// microsecond ExposureTime also refuses a fractional exposure of the series); frames on
// AVT's trigger, bit 0 of a big-endian register (it reads 0x80000000 where the fake camera wants
// TriggerMode 1).
// Basler: Aravis takes an ace's bounds from ExposureTimeRaw (raw steps of the 20 us timebase);
// irdist's are ExposureTimeAbs's, in microseconds.
const Vendor kBasler{"basler_aca1300_60gm", "IRDVBA01", "Mono12", 20.0, 1e6,
                     {"packet resend", "linearity"}, true,
                     "(ExposureTimeAbs); Aravis reported [1, 50000]"};
const Vendor kFlir{"flir_bfs_pge_19s4m", "IRDVFL01", "Mono12p", 5.0, 3e7,
                   {"packet resend", "linearity"}, true};
const Vendor kAvt{"avt_mako_g125b", "IRDVAV01", "Mono12", 12.0, 6e7,
                  {"packet resend", "triggered frames", "linearity"}, false};

void PrintTo(const Vendor& vendor, std::ostream* out) { *out << vendor.fixture; }

CameraSettings Settings(const Vendor& vendor) {
  CameraSettings settings;
  settings.pixel_format = vendor.pixel_format;
  settings.trigger_source = "Software";
  settings.width = 256;
  settings.height = 128;
  settings.exposure_us = 5000.0;
  return settings;
}

// The fake camera serving the vendor's file, powered up as the model would be.
class VendorCamera : public testing::VendorFakeCamera {
 public:
  explicit VendorCamera(const Vendor& vendor)
      : testing::VendorFakeCamera(vendor.fixture, vendor.serial) {}
};

std::set<std::string> FailedRows(const std::vector<CameraCheck>& checks) {
  std::set<std::string> failed;
  for (const CameraCheck& check : checks) {
    if (!check.passed) failed.insert(check.name);
  }
  return failed;
}

// The features irdist saved and set (its read-back's keys, irdist's own notes left out).
std::vector<std::string> SetFeatures(AravisCamera& camera) {
  std::vector<std::string> features;
  for (const auto& [feature, value] : camera.ReadBackFeatures()) {
    if (feature.rfind("irdist.", 0) != 0) features.push_back(feature);
  }
  return features;
}

// Opens the camera, configures it as a run would, and returns the features it saved and set,
// after putting it back as found (`outcome`: what LeaveAsFound said).
std::vector<std::string> ConfigureAndLeave(const Vendor& vendor, std::string* outcome) {
  auto camera = AravisCamera::Open("127.0.0.1", vendor.serial);
  camera->Configure(Settings(vendor));
  const std::vector<std::string> features = SetFeatures(*camera);
  *outcome = camera->LeaveAsFound(true);
  return features;
}

class VendorFiles : public ::testing::TestWithParam<Vendor> {};

// Configure takes the file: automatic controls off, the pixel pipeline neutral, the frame-rate
// limit off, the frame trigger on Software, the pixel format asked for, the exposure's bounds in
// microseconds.
TEST_P(VendorFiles, ConfigureTakesIt) {
  const Vendor& vendor = GetParam();
  VendorCamera fake(vendor);
  auto camera = AravisCamera::Open("127.0.0.1", vendor.serial);
  camera->Configure(Settings(vendor));
  const auto features = camera->ReadBackFeatures();
  EXPECT_EQ(features.at("PixelFormat"), vendor.pixel_format);
  EXPECT_EQ(features.at("TriggerSelector"), "FrameStart");
  EXPECT_EQ(features.at("TriggerMode"), "On");
  EXPECT_EQ(features.at("TriggerSource"), "Software");
  EXPECT_EQ(features.at("irdist.PixelPipeline"), "neutral");
  for (const char* off : {"ExposureAuto", "GainAuto"}) {
    if (features.count(off) != 0) {
      EXPECT_EQ(features.at(off), "Off") << off;
    }
  }
  if (features.count("AcquisitionFrameRateEnable") != 0) {
    EXPECT_EQ(features.at("AcquisitionFrameRateEnable"), "false");
  }
  if (features.count("ExposureMode") != 0) {
    EXPECT_EQ(features.at("ExposureMode"), "Timed");
  }
  const auto [min_us, max_us] = camera->ExposureBoundsUs();
  EXPECT_NEAR(min_us, vendor.min_us, 1e-6);
  EXPECT_NEAR(max_us, vendor.max_us, 1e-3);
  EXPECT_NE(features.at("irdist.ExposureBounds").find(vendor.bounds_note), std::string::npos)
      << features.at("irdist.ExposureBounds");
  if (features.count("AcquisitionMode") != 0) {
    EXPECT_EQ(features.at("AcquisitionMode"), "Continuous");
  }
}

// Every feature irdist saved is as found once it is done: read by another client before a
// configured session and after it.
TEST_P(VendorFiles, EverySavedFeatureIsPutBackAsFound) {
  const Vendor& vendor = GetParam();
  VendorCamera fake(vendor);
  std::string outcome;
  const std::vector<std::string> features = ConfigureAndLeave(vendor, &outcome);  // the list
  ASSERT_GT(features.size(), 10u);
  std::map<std::string, std::string> found;
  {
    OtherClient before;
    found = before.Read(features);
  }
  ConfigureAndLeave(vendor, &outcome);
  EXPECT_EQ(outcome, "The camera was put back as it was found.");
  OtherClient after;
  const std::map<std::string, std::string> left = after.Read(features);
  for (const auto& [feature, value] : found) EXPECT_EQ(left.at(feature), value) << feature;
}

// camera-test passes every row the fake camera can pass and fails exactly those it cannot, and
// puts the camera back.
TEST_P(VendorFiles, CameraTestPassesWhatTheFakeCameraCan) {
  const Vendor& vendor = GetParam();
  VendorCamera fake(vendor);
  auto camera = AravisCamera::Open("127.0.0.1", vendor.serial);
  const std::vector<CameraCheck> checks = CheckCamera(*camera);
  EXPECT_EQ(FailedRows(checks), vendor.cannot) << CameraCheckTable(checks);
  EXPECT_FALSE(camera->streaming());
}

// A bracket through the file's trigger, the exposure read back when no chunk comes (the fake
// camera sends none, whatever the file declares): every frame taken at its exposure.
TEST_P(VendorFiles, ABracketGetsItsFramesWithTheChunkFallback) {
  const Vendor& vendor = GetParam();
  if (!vendor.frames) GTEST_SKIP() << vendor.fixture << ": the fake camera frames no trigger";
  VendorCamera fake(vendor);
  auto camera = AravisCamera::Open("127.0.0.1", vendor.serial);
  camera->Configure(Settings(vendor));
  BracketOptions options;
  options.exposures_us = {4000.0, 12000.0, 8000.0};
  options.trigger_source = "Software";
  options.frame_timeout = std::chrono::milliseconds(2000);
  BracketCapture capture(*camera, options);
  for (int bracket = 0; bracket < 2; ++bracket) {
    const BracketResult result = capture.Capture([&](int) { camera->SoftwareTrigger(); });
    ASSERT_TRUE(result.complete) << result.BriefReport();
    ASSERT_EQ(result.frames.size(), 3u);
    for (std::size_t i = 0; i < result.frames.size(); ++i) {
      EXPECT_NEAR(result.frames[i].actual_exposure_us, options.exposures_us[i], 1.0) << i;
      EXPECT_FALSE(result.frames[i].exposure_from_chunk) << i;
    }
  }
  camera->StopStream();
  // Both files declare exposure chunks: the fallback is said once, naming the chunk.
  EXPECT_NE(capture.stats().exposure_notice.find("without its ChunkExposureTime chunk"),
            std::string::npos)
      << capture.stats().exposure_notice;
}

INSTANTIATE_TEST_SUITE_P(RealFiles, VendorFiles, ::testing::Values(kBasler, kFlir, kAvt),
                         [](const ::testing::TestParamInfo<Vendor>& info) {
                           return std::string(info.param.fixture);
                         });

// Teledyne DALSA's Shad-o-Box (an X-ray detector: no trigger, no exposure feature, a read-only
// region): Configure refuses it, naming why, and leaves it as found; camera-test names each lack.
TEST(VendorFileWithoutTrigger, ShadoBoxIsRefusedNamingWhatItLacks) {
  const Vendor dalsa{"dalsa_shadobox", "IRDVDA01", "Mono12Packed", 0, 0, {}, false};
  VendorCamera fake(dalsa);
  auto camera = AravisCamera::Open("127.0.0.1", dalsa.serial);
  EXPECT_EQ(camera->Identity().vendor, "Teledyne DALSA");
  try {
    camera->Configure(Settings(dalsa));
    FAIL() << "expected CameraError";
  } catch (const CameraError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("Width is read-only"), std::string::npos) << message;
    EXPECT_NE(message.find("put back as it was found"), std::string::npos) << message;
  }
  const std::vector<CameraCheck> checks = CheckCamera(*camera);
  const std::set<std::string> failed = FailedRows(checks);
  for (const char* row : {"exposure time", "frame trigger", "line trigger input", "setup"}) {
    EXPECT_EQ(failed.count(row), 1u) << row << "\n" << CameraCheckTable(checks);
  }
  EXPECT_EQ(failed.count("camera put back"), 0u) << CameraCheckTable(checks);
}

}  // namespace
}  // namespace irdist
