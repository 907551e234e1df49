// Tests of app/devices/camera_test.cc (`irdist camera-test`): the table against Aravis's fake
// camera with the vendor-style GenICam files of tests/acquisition/genicam/: a camera irdist can use
// passes every check, the minimal one without a trigger fails the trigger checks and the setup,
// each failure with its fix.
#include "app/devices/camera_test.h"

#include <gtest/gtest.h>

#include <string>

#include "acquisition/aravis_camera.h"
#include "tests/acquisition/fake_camera_process.h"

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
    EXPECT_TRUE(check.passed) << check.name << ": " << check.found;
  }
  EXPECT_NE(Find(checks, "pixel format").found.find("Mono12p"), std::string::npos);
  EXPECT_NE(Find(checks, "automatic controls off").found.find("ExposureAuto Continuous"),
            std::string::npos);
  EXPECT_NE(Find(checks, "trigger in readout").found.find("ReadOut"), std::string::npos);
  EXPECT_EQ(Find(checks, "triggered frames").found, "3 of 3 software-triggered");
  const std::string table = CameraCheckTable(checks);
  EXPECT_NE(table.find("PASS  setup"), std::string::npos) << table;
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

}  // namespace
}  // namespace irdist
