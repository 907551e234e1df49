#include "app/station_cmd.h"

#include <gtest/gtest.h>

#include <sstream>

#include "app/errors.h"
#include "sim/station_emulator.h"
#include "sim/world.h"

namespace irdist {
namespace {

// `irdist station` on the virtual rig's file with its station's port given by --port (the
// emulator in this process; no camera is started).
class StationCommand : public ::testing::Test {
 protected:
  StationCommand() : world_(100.0), emulator_(world_, sim::EmulatorOptions{}) {
    port_ = emulator_.Start();
  }
  std::string Run(const std::string& action, std::vector<double> values = {}) {
    StationArgs args;
    args.rig = std::string(IRDIST_SOURCE_DIR) + "/recipes/rigs/virtual.yaml";
    args.action = action;
    args.values = std::move(values);
    args.ports = {"station=" + port_};
    std::ostringstream out, err;
    RunStation(args, {out, err});
    return out.str();
  }
  sim::World world_;
  sim::StationEmulator emulator_;
  std::string port_;
};

TEST_F(StationCommand, MovesHomingFirstAndReportsThePose) {
  const std::string out = Run("move", {1800.0, 5.0, 0.0});
  EXPECT_NEAR(world_.Pose().slide_mm, 1800.0, 1e-6);
  EXPECT_NEAR(world_.Pose().pan_deg, 5.0, 1e-6);
  EXPECT_NE(out.find("position: slide 1800.00 mm, pan 5.00 deg"), std::string::npos) << out;
}

TEST_F(StationCommand, TheCurrentStaysOnUntilOff) {
  Run("current", {300.0});
  EXPECT_DOUBLE_EQ(world_.Pose().bias_ma, 300.0);  // the command ended; the IRED is still on
  Run("off");
  EXPECT_DOUBLE_EQ(world_.Pose().bias_ma, 0.0);
}

TEST_F(StationCommand, RefusesAPoseOutsideTheRigsLimitsBeforeMoving) {
  EXPECT_THROW(Run("move", {5000.0, 0.0, 0.0}), RecipeError);
  EXPECT_THROW(Run("move", {2000.0}), UsageError);
  EXPECT_FALSE(world_.Pose().moving);
}

TEST_F(StationCommand, AnUnknownDeviceInPortIsAUsageError) {
  StationArgs args;
  args.rig = std::string(IRDIST_SOURCE_DIR) + "/recipes/rigs/virtual.yaml";
  args.action = "status";
  args.ports = {"slide=" + port_};
  std::ostringstream out, err;
  EXPECT_THROW(RunStation(args, {out, err}), UsageError);
}

}  // namespace
}  // namespace irdist
