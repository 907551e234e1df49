#include "sim/virtual_rig.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <sstream>

#include "base/input_error.h"
#include "sim/camera_server.h"
#include "sim/station_emulator.h"
#include "sim/trajectory_file.h"
#include "tests/loopback_gvcp.h"
#include "tests/sim/pty_host.h"

namespace irdist::sim {
namespace {

const std::string kRig = std::string(IRDIST_SOURCE_DIR) + "/recipes/rigs/virtual.yaml";

TEST(VirtualRigOverrides, DefaultsAreValid) {
  std::string why;
  EXPECT_TRUE(VirtualRigOverrides{}.IsValid(&why)) << why;
  VirtualRigOverrides bad;
  bad.time_scale = 0.0;
  EXPECT_FALSE(bad.IsValid(&why));
  VirtualRigOverrides no_file;
  no_file.trajectory_csv = "";
  EXPECT_FALSE(no_file.IsValid(&why));
}

TEST(VirtualRig, StartsCameraAndStationFromTheRigFile) {
  ASSERT_TRUE(irdist::testing::WaitForLoopbackGvcpPort(std::chrono::seconds(120)));
  VirtualRigOverrides overrides;
  overrides.time_scale = 20.0;
  overrides.serial = "IRDRIG7";
  overrides.seed = 5;
  std::unique_ptr<VirtualRig> rig = VirtualRig::Start(kRig, overrides);
  const VirtualRigInfo& info = rig->Info();
  EXPECT_EQ(info.camera_id, "Aravis-Fake-IRDRIG7");
  EXPECT_EQ(info.camera_address, "127.0.0.1");
  EXPECT_EQ(info.serial, "IRDRIG7");
  EXPECT_EQ(info.time_scale, 20.0);
  EXPECT_EQ(rig->physics().sensor.seed, 5u);
  EXPECT_TRUE(rig->camera().running());
  EXPECT_NE(info.BriefReport().find("camera: Aravis-Fake-IRDRIG7"), std::string::npos);
  ASSERT_NE(rig->station(), nullptr);
  ASSERT_EQ(info.station_port.rfind("/dev/pts/", 0), 0u) << info.station_port;
  const int fd = ::open(info.station_port.c_str(), O_RDWR | O_NOCTTY);
  EXPECT_GE(fd, 0) << "cannot open the station pty " << info.station_port;
  if (fd >= 0) ::close(fd);
  // The World is shared: what the station sets is what the camera sees.
  rig->world().SetCurrent(480);
  EXPECT_EQ(rig->world().Pose().bias_ma, 480);
  rig->Stop();
  EXPECT_FALSE(rig->camera().running());
  EXPECT_TRUE(irdist::testing::WaitForLoopbackGvcpPort(std::chrono::seconds(5)))
      << "Stop() left the port bound";
}

TEST(VirtualRig, DescribesGroundTruthOverTheTableThreeGrid) {
  // Ground truth needs no running rig: Describe uses the same renderer as the camera.
  const RigPhysics physics = LoadRigPhysics(kRig);
  const Renderer renderer(physics);
  for (double d : {1500.0, 2000.0, 2500.0, 3000.0}) {
    double last_minor = 1e9;
    for (double theta = 0; theta <= 35; theta += 5) {
      PoseState pose;
      pose.slide_mm = d;
      pose.pan_deg = theta;
      pose.bias_ma = 500;
      const GroundTruth g = renderer.Describe(pose, 0.036, PixelFormat::kMono12);
      EXPECT_GE(g.major_px, 8.0);
      EXPECT_FALSE(g.saturated) << g.BriefReport();
      EXPECT_LT(g.minor_px, last_minor + 1e-9);  // foreshortening grows with theta
      last_minor = g.minor_px;
      EXPECT_NEAR(g.theta_deg, theta, 1e-9);
    }
  }
}

const std::string kLab = std::string(IRDIST_SOURCE_DIR) + "/recipes/rigs/virtual-lab.yaml";

TEST(VirtualRig, VirtualLabStartsItsThreeDeviceEmulatorsOnTheOneWorld) {
  ASSERT_TRUE(irdist::testing::WaitForLoopbackGvcpPort(std::chrono::seconds(120)));
  VirtualRigOverrides overrides;
  overrides.time_scale = 20.0;
  std::unique_ptr<VirtualRig> rig = VirtualRig::Start(kLab, overrides);
  const VirtualRigInfo& info = rig->Info();
  EXPECT_EQ(rig->station(), nullptr);
  EXPECT_EQ(info.station_port, "");
  ASSERT_EQ(info.device_ports.size(), 3u);
  for (const char* name : {"slide", "head", "source"}) {
    ASSERT_EQ(info.device_ports.count(name), 1u) << name;
    EXPECT_EQ(info.device_ports.at(name).rfind("/dev/pts/", 0), 0u);
    EXPECT_NE(rig->device(name), nullptr);
    EXPECT_NE(info.BriefReport().find(std::string("device ") + name + ": /dev/pts/"),
              std::string::npos);
  }
  World& world = rig->world();
  testing::PtyHost slide(info.device_ports.at("slide"));
  EXPECT_EQ(slide.Ask("/1 1 home\n"), "@01 1 OK BUSY WR 0");
  EXPECT_TRUE(testing::WaitFor([&] { return world.Pose().slide_mm < 1000.001; }));
  // The world reaches the home position before the device ends its homing (and clears WR):
  // wait for the device itself to say IDLE.
  EXPECT_TRUE(testing::WaitFor(
      [&] { return slide.Ask("/1 1\n").find(" IDLE ") != std::string::npos; }));
  // 1000 mm further along the slide: 1000 / 0.09921875 um microsteps.
  EXPECT_EQ(slide.Ask("/1 1 move abs 10078740\n"), "@01 1 OK BUSY -- 0");
  EXPECT_TRUE(testing::WaitFor([&] { return std::abs(world.Pose().slide_mm - 2000.0) < 1e-3; }));
  testing::PtyHost head(info.device_ports.at("head"));
  EXPECT_EQ(head.Ask("PP1000 A\r\n"), "*");
  EXPECT_EQ(head.ReadLine(5000), "*");
  EXPECT_NEAR(world.Pose().pan_deg, 1000 * 92.5714 / 3600.0, 1e-6);
  testing::PtyHost source(info.device_ports.at("source"));
  source.Send("*RST;:SOUR:FUNC CURR;:SOUR:CURR 0.4;:SENS:VOLT:PROT 3;:OUTP ON\n");
  EXPECT_EQ(source.Ask("*OPC?\n"), "1");
  EXPECT_NEAR(world.Pose().bias_ma, 400.0, 1e-9);
  rig->Stop();
  EXPECT_TRUE(irdist::testing::WaitForLoopbackGvcpPort(std::chrono::seconds(5)));
}

TEST(VirtualRig, ADeviceWithoutAnEmulatorIsAnInputError) {
  ASSERT_TRUE(irdist::testing::WaitForLoopbackGvcpPort(std::chrono::seconds(120)));
  std::ifstream in(kLab);
  std::stringstream text;
  text << in.rdbuf();
  std::string rig = text.str();
  rig.replace(rig.find("driver: flir_ptu"), 16, "driver: acme_ptu");
  const std::string path = ::testing::TempDir() + "virtual-lab-acme.yaml";
  std::ofstream(path) << rig;
  try {
    VirtualRig::Start(path);
    FAIL() << "a driver without an emulator was accepted";
  } catch (const InputError& e) {
    EXPECT_GT(e.Line(), 0);
    EXPECT_NE(std::string(e.what()).find("acme_ptu"), std::string::npos) << e.what();
  }
}

// docs/virtual-rig.md "Truth of a moving target": the station's trajectory logged from the
// start to the file the override names; a reboot halts the axes where they stand (new rows).
TEST(VirtualRig, LogsTheStationsTrajectoryFromItsPowerUp) {
  ASSERT_TRUE(irdist::testing::WaitForLoopbackGvcpPort(std::chrono::seconds(120)));
  VirtualRigOverrides overrides;
  overrides.time_scale = 20.0;
  overrides.trajectory_csv = ::testing::TempDir() + "virtual-rig-trajectory.csv";
  ::unlink(overrides.trajectory_csv->c_str());
  std::unique_ptr<VirtualRig> rig = VirtualRig::Start(kRig, overrides);
  EXPECT_EQ(rig->Info().trajectory_csv, *overrides.trajectory_csv);
  EXPECT_NE(rig->Info().BriefReport().find("trajectory: " + *overrides.trajectory_csv),
            std::string::npos);
  ASSERT_NE(rig->station(), nullptr);
  rig->station()->Reboot();
  const Trajectory logged = ReadTrajectoryFile(*overrides.trajectory_csv);
  for (RigAxis axis : {RigAxis::kSlide, RigAxis::kPan, RigAxis::kTilt}) {
    EXPECT_EQ(logged.Profiles(axis).size(), 2u) << RigAxisName(axis);  // power-up, reboot
  }
  const TrajectoryPoint now = logged.At(rig->world().clock().Now());
  ASSERT_TRUE(now.known);
  EXPECT_EQ(now.slide_mm, rig->world().Pose().slide_mm);
  EXPECT_EQ(rig->world().TrajectoryLogError(), "");
  rig->Stop();
  // The file is the rig's: a second rig refuses to overwrite it.
  EXPECT_TRUE(irdist::testing::WaitForLoopbackGvcpPort(std::chrono::seconds(5)));
  EXPECT_THROW(VirtualRig::Start(kRig, overrides), TrajectoryFileError);
  ::unlink(overrides.trajectory_csv->c_str());
}

TEST(VirtualRig, MissingRigFileIsATypedError) {
  EXPECT_THROW(VirtualRig::Start("/nonexistent.yaml"), RigFileError);
}

}  // namespace
}  // namespace irdist::sim
