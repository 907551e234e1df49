// Tests of app/runs/linearity_check.cc: a calibration's first-pose linearity series on the virtual
// camera (software-fired here; a run fires the rig's trigger): a linear camera passes and the
// recording keeps the figures; a gamma curve the camera cannot switch off stops the calibration
// naming the probable causes, unless --allow-nonlinear.
#include "app/runs/linearity_check.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "acquisition/aravis_camera.h"
#include "sim/virtual_rig.h"
#include "tests/loopback_gvcp.h"
#include "tests/virtual_rig_with.h"

namespace irdist {
namespace {

struct Outcome {
  LinearityResult result;
  std::string error;  // the CameraError's message, when one was thrown
  std::string file;   // linearity.yaml as written
  std::string line;   // what was printed
};

Outcome FirstPose(const std::string& rig_path, const char* serial, bool allow) {
  testing::LoopbackGvcpLock lock;
  sim::VirtualRigOverrides overrides;
  overrides.serial = serial;
  auto rig = sim::VirtualRig::Start(rig_path, overrides);
  rig->world().SetPose(1500.0, 0.0, 0.0, false);
  rig->world().SetCurrent(500.0);
  auto camera = AravisCamera::Open(rig->Info().camera_address, rig->Info().serial);
  CameraSettings settings;
  settings.pixel_format = "Mono12";
  settings.trigger_source = "Software";
  camera->Configure(settings);
  const std::string dir = ::testing::TempDir() + "/linearity_" + serial;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  Outcome out;
  std::ostringstream printed;
  try {
    out.result = CheckFirstPoseLinearity(
        *camera, [&camera] { camera->SoftwareTrigger(); }, {dir, allow, 8000.0, 12}, printed);
  } catch (const CameraError& error) {
    out.error = error.what();
  }
  std::ifstream file(dir + "/linearity.yaml");
  out.file.assign(std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>());
  out.line = printed.str();
  return out;
}

// The options refuse each bad field by name.
TEST(FirstPoseLinearityOptions, RefusesEachBadFieldByName) {
  FirstPoseLinearityOptions o;
  o.recording_dir = "/tmp/recording";
  o.probe_exposure_us = 8000.0;
  std::string why;
  EXPECT_TRUE(o.IsValid(&why)) << why;
  FirstPoseLinearityOptions bad = o;
  bad.recording_dir.clear();
  EXPECT_FALSE(bad.IsValid(&why));
  EXPECT_NE(why.find("recording_dir"), std::string::npos) << why;
  bad = o;
  bad.probe_exposure_us = 0.0;
  EXPECT_FALSE(bad.IsValid(&why));
  EXPECT_NE(why.find("probe_exposure_us"), std::string::npos) << why;
  bad = o;
  bad.bit_depth = 17;
  EXPECT_FALSE(bad.IsValid(&why));
  EXPECT_NE(why.find("bit_depth"), std::string::npos) << why;
}

TEST(FirstPoseLinearity, ALinearCameraPassesAndTheRecordingKeepsTheSeries) {
  const Outcome o = FirstPose(testing::VirtualRigWithCameraKeys("fp_linear", ""), "IRDLIN1", false);
  EXPECT_EQ(o.error, "");
  ASSERT_TRUE(o.result.measured) << o.result.why;
  EXPECT_LE(o.result.error_percent, 0.3);
  EXPECT_NE(o.file.find("passed: true"), std::string::npos) << o.file;
  EXPECT_NE(o.file.find("linearity_error_percent: "), std::string::npos) << o.file;
  EXPECT_NE(o.file.find("dark_offset_dn: "), std::string::npos) << o.file;
  EXPECT_EQ(o.result.points.size(), 6u);
  EXPECT_NE(o.line.find("Camera linearity at the first pose: linearity error"), std::string::npos);
}

TEST(FirstPoseLinearity, AFixedGammaStopsTheCalibrationUnlessAllowed) {
  const std::string rig = testing::VirtualRigWithCameraKeys("fp_gamma", "    fixed_gamma: 0.45\n");
  const Outcome refused = FirstPose(rig, "IRDLIN2", false);
  EXPECT_NE(refused.error.find("not linear at the first pose"), std::string::npos) << refused.error;
  EXPECT_NE(refused.error.find("a LUT, a gamma curve, a contrast feature or saturation"),
            std::string::npos);
  EXPECT_NE(refused.error.find("--allow-nonlinear"), std::string::npos);
  EXPECT_NE(refused.file.find("passed: false"), std::string::npos) << refused.file;
  const Outcome allowed = FirstPose(rig, "IRDLIN3", true);
  EXPECT_EQ(allowed.error, "");
  EXPECT_GT(allowed.result.error_percent, 1.0);
}

TEST(FirstPoseLinearity, TheFileHoldsEveryPoint) {
  LinearityResult r;
  r.measured = true;
  r.error_percent = 0.25;
  r.points = {{1000.0, 300.0}, {2000.0, 540.0}};
  const std::string yaml = LinearityYaml(r);
  EXPECT_NE(yaml.find("  - [1000, 300]\n  - [2000, 540]\n"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("measured: true"), std::string::npos);
}

TEST(FirstPoseLinearity, AResumeMeasuresAgainUnlessTheSeriesPassed) {
  const std::string dir = ::testing::TempDir() + "/linearity_resume";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  EXPECT_TRUE(NeedsFirstPoseLinearity(dir, false));
  EXPECT_TRUE(NeedsFirstPoseLinearity(dir, true));  // cut before the series was kept
  LinearityResult failed;
  failed.measured = true;
  failed.error_percent = 8.0;
  std::ofstream(dir + "/linearity.yaml") << LinearityYaml(failed);
  EXPECT_TRUE(NeedsFirstPoseLinearity(dir, true));  // refused: a resume measures again
  LinearityResult passed = failed;
  passed.error_percent = 0.1;
  std::ofstream(dir + "/linearity.yaml") << LinearityYaml(passed);
  EXPECT_FALSE(NeedsFirstPoseLinearity(dir, true));
  EXPECT_TRUE(NeedsFirstPoseLinearity(dir, false));  // a new recording always measures
}

}  // namespace
}  // namespace irdist
