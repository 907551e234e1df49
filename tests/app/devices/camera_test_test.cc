// Tests of app/devices/camera_test.cc (`irdist camera-test`): the table against Aravis's fake
// camera with the vendor-style GenICam files of tests/acquisition/genicam/: a camera irdist can use
// passes every check, the minimal one without a trigger fails the trigger checks and the setup,
// each failure with its fix.
#include "app/devices/camera_test.h"

#include <gtest/gtest.h>

#include <arv.h>

#include <fstream>
#include <iostream>
#include <stdexcept>
#include <string>

#include "acquisition/aravis_camera.h"
#include "sim/virtual_rig.h"
#include "tests/acquisition/fake_camera_process.h"
#include "tests/loopback_gvcp.h"
#include "tests/virtual_rig_with.h"

namespace irdist {
namespace {

std::string Genicam(const char* file) {
  return std::string(IRDIST_SOURCE_DIR) + "/tests/acquisition/genicam/" + file;
}

const CameraCheck& Find(const std::vector<CameraCheck>& checks, const std::string& name) {
  for (const CameraCheck& check : checks) {
    if (check.name == name) return check;
  }
  static const CameraCheck missing{"(missing)", false, "", ""};
  ADD_FAILURE() << "no check named " << name;
  return missing;
}

std::vector<CameraCheck> ChecksOf(const char* genicam, const char* serial) {
  testing::FakeCameraProcess fake(serial, {"-g", Genicam(genicam)});
  auto camera = AravisCamera::Open("127.0.0.1", fake.serial());
  return CheckCamera(*camera);
}

TEST(CameraTest, FlirStyleCameraPassesEveryCheck) {
  const std::vector<CameraCheck> checks = ChecksOf("flir_style.xml", "IRDCT01");
  for (const CameraCheck& check : checks) {
    if (check.name == "packet resend") continue;  // Aravis's fake camera: its own declaration
    // Aravis's fake camera draws a moving ramp whose scale grows with log(exposure): not linear.
    if (check.name == "linearity") continue;
    EXPECT_TRUE(check.passed) << check.name << ": " << check.found;
  }
  EXPECT_NE(Find(checks, "pixel format").found.find("Mono12p"), std::string::npos);
  EXPECT_NE(Find(checks, "automatic controls off").found.find("ExposureAuto Continuous"),
            std::string::npos);
  EXPECT_NE(Find(checks, "trigger in readout").found.find("ReadOut"), std::string::npos);
  EXPECT_EQ(Find(checks, "triggered frames").found.rfind("3 of 3 software-triggered, ", 0), 0u)
      << Find(checks, "triggered frames").found;
  const std::string table = CameraCheckTable(checks);
  EXPECT_NE(table.find("PASS  setup"), std::string::npos) << table;
}

// camera-test configures as a run does: the rig file's camera settings when given (region,
// format, exposure evidence), else a run's defaults (the whole sensor) with the deepest format.
TEST(CameraTest, TheSetupIsARunsConfigure) {
  testing::FakeCameraProcess fake("IRDCT09");
  auto camera = AravisCamera::Open("127.0.0.1", fake.serial());
  CameraSettings run;  // as app/inputs/camera_settings.h makes it from a rig file
  run.pixel_format = "Mono16";
  run.trigger_source = "Line0";
  run.offset_x = 16;
  run.offset_y = 8;
  run.width = 256;
  run.height = 128;
  run.exposure_check = ExposureCheck::kReadback;
  const std::vector<CameraCheck> checks = CheckCamera(*camera, &run);
  const CameraCheck& setup = Find(checks, "setup");
  EXPECT_TRUE(setup.passed) << setup.found;
  EXPECT_EQ(setup.found,
            "Mono16, 256 x 128 at (16, 8), Software trigger (a run fires Line0); the rig file's "
            "camera settings");
  const CameraCheck& frames = Find(checks, "triggered frames");
  EXPECT_TRUE(frames.passed) << frames.found;
  EXPECT_NE(frames.found.find("(readback)"), std::string::npos) << frames.found;
  const std::vector<CameraCheck> defaults = CheckCamera(*camera);
  EXPECT_EQ(Find(defaults, "setup").found,
            "Mono16, the whole sensor, Software trigger; a run's defaults (no rig file)");
  EXPECT_TRUE(Find(defaults, "triggered frames").passed) << Find(defaults, "triggered frames").found;
}

TEST(CameraTest, SingleTriggerCameraPassesTheTriggerChecks) {
  const std::vector<CameraCheck> checks = ChecksOf("single_trigger.xml", "IRDCT02");
  EXPECT_TRUE(Find(checks, "frame trigger").passed) << Find(checks, "frame trigger").found;
  EXPECT_TRUE(Find(checks, "line trigger input").passed);
  EXPECT_TRUE(Find(checks, "setup").passed) << Find(checks, "setup").found;
}

TEST(CameraTest, MinimalCameraFailsTheTriggerChecksEachWithItsFix) {
  const std::vector<CameraCheck> checks = ChecksOf("minimal.xml", "IRDCT03");
  for (const char* name : {"frame trigger", "line trigger input", "setup"}) {
    EXPECT_FALSE(Find(checks, name).passed) << name;
    EXPECT_FALSE(Find(checks, name).fix.empty()) << name;
  }
  EXPECT_TRUE(Find(checks, "pixel format").passed);
  EXPECT_TRUE(Find(checks, "exposure time").passed);
  const std::string table = CameraCheckTable(checks);
  EXPECT_NE(table.find("FAIL  frame trigger"), std::string::npos) << table;
  EXPECT_NE(table.find("fix: irdist triggers each frame"), std::string::npos) << table;
}

TEST(CameraTest, ExposureStartOnlyCameraPassesTheTriggerChecksAndTheSetup) {
  const std::vector<CameraCheck> checks = ChecksOf("exposure_start_only.xml", "IRDCT04");
  EXPECT_TRUE(Find(checks, "frame trigger").passed) << Find(checks, "frame trigger").found;
  EXPECT_NE(Find(checks, "frame trigger").found.find("frame trigger ExposureStart"),
            std::string::npos);
  EXPECT_TRUE(Find(checks, "setup").passed) << Find(checks, "setup").found;
  EXPECT_EQ(Find(checks, "triggered frames").found.rfind("3 of 3 software-triggered, ", 0), 0u)
      << Find(checks, "triggered frames").found;
}

TEST(CameraTest, ReadOnlySelectorCameraKeepsItsWholeTable) {
  const std::vector<CameraCheck> checks = ChecksOf("read_only_selector.xml", "IRDCT05");
  EXPECT_TRUE(Find(checks, "frame trigger").passed) << Find(checks, "frame trigger").found;
  EXPECT_TRUE(Find(checks, "line trigger input").passed);
  EXPECT_TRUE(Find(checks, "other triggers off").passed);
  // Its locked BlackLevel fails the setup, with the feature and the fix named; the rows after it
  // are still there.
  const CameraCheck& setup = Find(checks, "setup");
  EXPECT_FALSE(setup.passed);
  EXPECT_NE(setup.found.find("BlackLevel is locked"), std::string::npos) << setup.found;
  EXPECT_EQ(setup.found.find(".cc:"), std::string::npos) << setup.found;
  EXPECT_FALSE(Find(checks, "linearity").passed);
  EXPECT_TRUE(Find(checks, "camera put back").passed) << Find(checks, "camera put back").found;
}

// A check that throws fails alone: its row carries the error and its fix, every other row runs.
TEST(CameraTest, AnExceptionInOneCheckLeavesTheTableWhole) {
  testing::FakeCameraProcess fake("IRDCT06", {"-g", Genicam("flir_style.xml")});
  auto camera = AravisCamera::Open("127.0.0.1", fake.serial());
  std::vector<CameraCheckStep> steps = CameraCheckSteps();
  const std::size_t before = steps.size();
  steps.insert(steps.begin() + 2,
               {"exploding check", "the fix of the exploding check",
                [](AravisCamera&) -> std::vector<CameraCheck> {
                  throw std::runtime_error("the check's own failure");
                }});
  const std::vector<CameraCheck> checks = RunCameraChecks(*camera, steps);
  EXPECT_GE(checks.size(), before + 1);
  const CameraCheck& exploded = Find(checks, "exploding check");
  EXPECT_FALSE(exploded.passed);
  EXPECT_EQ(exploded.found, "the check's own failure");
  EXPECT_EQ(exploded.fix, "the fix of the exploding check");
  EXPECT_TRUE(Find(checks, "setup").passed);
  EXPECT_TRUE(Find(checks, "triggered frames").passed);
  const std::string table = CameraCheckTable(checks);
  EXPECT_NE(table.find("FAIL  exploding check"), std::string::npos) << table;
  EXPECT_NE(table.find("fix: the fix of the exploding check"), std::string::npos) << table;
  EXPECT_NE(table.find("PASS  triggered frames"), std::string::npos) << table;
}

TEST(CameraTest, RawMosaicFailsTheMonochromeRowWithItsFix) {
  const std::vector<CameraCheck> checks = ChecksOf("raw_mosaic.xml", "IRDCT07");
  const CameraCheck& colour = Find(checks, "monochrome sensor");
  EXPECT_FALSE(colour.passed);
  EXPECT_EQ(colour.found, "raw colour mosaic: PixelColorFilter BayerRG");
  EXPECT_NE(colour.fix.find("use a monochrome camera"), std::string::npos);
  EXPECT_FALSE(Find(checks, "setup").passed);
}

// --- the virtual camera (sim/), its blob lit -----------------------------------------------------


struct VirtualChecks {
  std::vector<CameraCheck> checks;
  std::string lut_after;  // LUTEnable as another client reads it after camera-test
};

VirtualChecks CheckVirtualCamera(const std::string& rig_path, const char* serial,
                                 double current_ma = 500.0) {
  irdist::testing::LoopbackGvcpLock lock;
  sim::VirtualRigOverrides overrides;
  overrides.serial = serial;
  auto rig = sim::VirtualRig::Start(rig_path, overrides);
  rig->world().SetPose(1500.0, 0.0, 0.0, false);
  rig->world().SetCurrent(current_ma);
  VirtualChecks out;
  {
    auto camera = AravisCamera::Open(rig->Info().camera_address, rig->Info().serial);
    out.checks = CheckCamera(*camera);
    std::cout << CameraCheckTable(out.checks);
  }
  GError* error = nullptr;
  ArvCamera* other = arv_camera_new(rig->Info().camera_address.c_str(), &error);
  if (other != nullptr) {
    out.lut_after = arv_camera_get_boolean(other, "LUTEnable", &error) ? "true" : "false";
    g_object_unref(other);
  }
  if (error != nullptr) g_error_free(error);
  return out;
}

TEST(CameraTest, VirtualCameraIsLinearWithinThreeTenthsOfAPercent) {
  const VirtualChecks v =
      CheckVirtualCamera(testing::VirtualRigWithCameraKeys("linear", ""), "IRDCTV1");
  const CameraCheck& linearity = Find(v.checks, "linearity");
  EXPECT_TRUE(linearity.passed) << linearity.found;
  EXPECT_NE(linearity.found.find("dark offset"), std::string::npos) << linearity.found;
  const std::size_t at = linearity.found.find("linearity error ");
  ASSERT_NE(at, std::string::npos) << linearity.found;
  EXPECT_LE(std::stod(linearity.found.substr(at + 16)), 0.3) << linearity.found;
  EXPECT_TRUE(Find(v.checks, "neutral pixel pipeline").passed);
  EXPECT_NE(Find(v.checks, "neutral pixel pipeline").found.find("LUTEnable false"),
            std::string::npos);
  EXPECT_TRUE(Find(v.checks, "monochrome sensor").passed);
}

// Chunks as a run meets them: the virtual camera's frames carry ChunkExposureTime (each exposure
// checked by it); with the chunks dropped camera-test's triggered frames fall back as a run does,
// and say so, instead of passing a camera a run would then reject.
TEST(CameraTest, VirtualCameraTriggeredFramesCarryTheRunsExposureEvidence) {
  const VirtualChecks with = CheckVirtualCamera(testing::VirtualRigWithCameraKeys("chunks", ""),
                                                "IRDCTV5");
  const CameraCheck& taken = Find(with.checks, "triggered frames");
  EXPECT_TRUE(taken.passed) << taken.found;
  EXPECT_NE(taken.found.find("checked by its ChunkExposureTime"), std::string::npos) << taken.found;
  const VirtualChecks without = CheckVirtualCamera(
      testing::VirtualRigWithCameraKeys("nochunks", "    drop_exposure_chunks_from_frame: 1\n"),
      "IRDCTV6");
  const CameraCheck& fallback = Find(without.checks, "triggered frames");
  EXPECT_TRUE(fallback.passed) << fallback.found;
  EXPECT_NE(fallback.found.find("exposures read back before each trigger (auto)"),
            std::string::npos) << fallback.found;
  EXPECT_NE(fallback.found.find("a run falls back the same way"), std::string::npos)
      << fallback.found;
}

// A LUT a previous user left on: switched off for the checks (linear again), and back on after.
TEST(CameraTest, VirtualCameraLutLeftOnIsSwitchedNeutralAndPutBack) {
  const VirtualChecks v =
      CheckVirtualCamera(testing::VirtualRigWithCameraKeys(
                             "lut", "    lut_enable: true\n    lut_gamma: 0.45\n"),
                         "IRDCTV2");
  const CameraCheck& pipeline = Find(v.checks, "neutral pixel pipeline");
  EXPECT_TRUE(pipeline.passed) << pipeline.found;
  EXPECT_NE(pipeline.found.find("LUTEnable true -> false"), std::string::npos) << pipeline.found;
  EXPECT_TRUE(Find(v.checks, "linearity").passed) << Find(v.checks, "linearity").found;
  EXPECT_TRUE(Find(v.checks, "camera put back").passed);
  EXPECT_EQ(v.lut_after, "true");
}

// A gamma curve the camera applies with no feature to switch it: the linearity row fails, naming
// the probable causes.
TEST(CameraTest, VirtualCameraFixedGammaFailsLinearity) {
  const VirtualChecks v =
      CheckVirtualCamera(testing::VirtualRigWithCameraKeys("gamma", "    fixed_gamma: 0.45\n"),
                         "IRDCTV3");
  const CameraCheck& linearity = Find(v.checks, "linearity");
  EXPECT_FALSE(linearity.passed) << linearity.found;
  EXPECT_NE(linearity.found.find("linearity error"), std::string::npos) << linearity.found;
  EXPECT_NE(linearity.fix.find("a LUT, a gamma curve, a contrast feature or saturation"),
            std::string::npos);
  const std::string table = CameraCheckTable(v.checks);
  EXPECT_NE(table.find("FAIL  linearity"), std::string::npos) << table;
}

// The IRED off: the linearity row says the scene has no light (and fails: nothing measured).
TEST(CameraTest, VirtualCameraWithoutLightSaysSo) {
  const VirtualChecks v =
      CheckVirtualCamera(testing::VirtualRigWithCameraKeys("dark", ""), "IRDCTV4", 0.0);
  const CameraCheck& linearity = Find(v.checks, "linearity");
  EXPECT_FALSE(linearity.passed);
  EXPECT_EQ(linearity.found.rfind("not measured: no light", 0), 0u) << linearity.found;
  EXPECT_NE(linearity.fix.find("lit scene"), std::string::npos);
  EXPECT_TRUE(Find(v.checks, "setup").passed);
}

}  // namespace
}  // namespace irdist
