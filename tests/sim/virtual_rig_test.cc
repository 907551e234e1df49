#include "sim/virtual_rig.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include "sim/camera_server.h"
#include "tests/loopback_gvcp.h"

namespace irdist::sim {
namespace {

const std::string kRig = std::string(IRDIST_SOURCE_DIR) + "/recipes/rigs/virtual.yaml";

TEST(VirtualRigOverrides, DefaultsAreValid) {
  std::string why;
  EXPECT_TRUE(VirtualRigOverrides{}.IsValid(&why)) << why;
  VirtualRigOverrides bad;
  bad.time_scale = 0.0;
  EXPECT_FALSE(bad.IsValid(&why));
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

TEST(VirtualRig, MissingRigFileIsATypedError) {
  EXPECT_THROW(VirtualRig::Start("/nonexistent.yaml"), RigFileError);
}

}  // namespace
}  // namespace irdist::sim
