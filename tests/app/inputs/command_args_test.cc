#include "app/inputs/command_args.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <sstream>
#include <string>

#include "app/devices/sim_command.h"
#include "app/devices/station_cmd.h"
#include "app/inputs/errors.h"
#include "app/live/snap_command.h"
#include "app/runs/plan_command.h"

namespace irdist {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

// IsValid's answer and its reason.
template <typename Args>
std::string Why(const Args& args) {
  std::string why;
  return args.IsValid(&why) ? "valid" : why;
}

TEST(CommandArgs, EveryCommandsDefaultsAreValid) {
  EXPECT_EQ(Why(CalibrateArgs{}), "valid");
  EXPECT_EQ(Why(ValidateArgs{}), "valid");
  EXPECT_EQ(Why(MeasureArgs{}), "valid");
  EXPECT_EQ(Why(SnapArgs{}), "valid");
  EXPECT_EQ(Why(ViewArgs{}), "valid");
  EXPECT_EQ(Why(PlanArgs{}), "valid");
  EXPECT_EQ(Why(SimArgs{}), "valid");
  EXPECT_EQ(Why(StationArgs{}), "valid");
  EXPECT_EQ(Why(StationTestArgs{}), "valid");
}

TEST(CommandArgs, TimeScaleIsTheRigsOrInsideItsRange) {
  for (double scale : {0.0, 0.01, 1.0, 1000.0}) {
    SimArgs sim;
    sim.time_scale = scale;
    EXPECT_EQ(Why(sim), "valid") << scale;
  }
  for (double scale : {-1.0, 0.001, 1000.5, kNan}) {
    CalibrateArgs calibrate;
    calibrate.time_scale = scale;
    EXPECT_NE(Why(calibrate).find("--time-scale"), std::string::npos) << scale;
  }
}

// Each of measure's numbers out of its range alone: refused, the flag named.
TEST(CommandArgs, MeasureNamesEachNumberOutsideItsBound) {
  const std::pair<std::string, std::function<void(MeasureArgs&)>> cases[] = {
      {"--t-ref-ms", [](MeasureArgs& a) { a.t_ref_ms = -8.0; }},
      {"--t-meas-ms", [](MeasureArgs& a) { a.t_meas_ms = {30.0, kNan}; }},
      {"--t-meas-ms", [](MeasureArgs& a) { a.t_meas_ms = {0.0}; }},
      {"--count", [](MeasureArgs& a) { a.count = -3; }},
      {"--duration", [](MeasureArgs& a) { a.duration_s = 1.0e6; }},
      {"--max-disk-gb", [](MeasureArgs& a) { a.max_disk_gb = -1.0; }},
      {"--exposure-ms", [](MeasureArgs& a) { a.exposure_ms = 2.0e5; }},
      {"--accel-psd", [](MeasureArgs& a) { a.accel_psd_mm2_per_s3 = kNan; }},
      {"--check-every", [](MeasureArgs& a) { a.check_every_s = -5.0; }},
      {"--at", [](MeasureArgs& a) { a.at = {2000.0, 10.0, 0.0}; }},
      {"--at", [](MeasureArgs& a) { a.at = {2000.0, 10.0, kNan, 500.0}; }},
      {"BIAS_MA", [](MeasureArgs& a) { a.at = {2000.0, 10.0, 0.0, -1.0}; }},
      {"--time-scale", [](MeasureArgs& a) { a.time_scale = -2.0; }},
  };
  for (const auto& [flag, spoil] : cases) {
    MeasureArgs args;
    spoil(args);
    EXPECT_NE(Why(args).find(flag), std::string::npos) << flag << ": " << Why(args);
  }
  MeasureArgs good;
  good.t_ref_ms = 8.0;
  good.t_meas_ms = {30.0, 32.0};
  good.count = 10;
  good.at = {2000.0, -10.0, 0.0, 500.0};
  EXPECT_EQ(Why(good), "valid");
}

TEST(CommandArgs, TheOtherCommandsNumbers) {
  SnapArgs snap;
  snap.exposure_ms = 0.0;  // snap has no "0 = default": its default is 8 ms
  EXPECT_NE(Why(snap).find("--exposure-ms"), std::string::npos);
  ViewArgs view;
  view.frames = -1;
  EXPECT_NE(Why(view).find("--frames"), std::string::npos);
  PlanArgs plan;
  plan.show_poses = -2;
  EXPECT_NE(Why(plan).find("--poses"), std::string::npos);
  plan.show_poses = -1;  // all
  EXPECT_EQ(Why(plan), "valid");
  StationArgs station;
  station.action = "move";
  station.values = {1500.0, kNan, 0.0};
  EXPECT_NE(Why(station).find("not finite"), std::string::npos);
  StationTestArgs board;
  board.baud = 0;
  EXPECT_NE(Why(board).find("--baud"), std::string::npos);
}

// The engines check before they read a file or start a device: the refusal is a UsageError naming
// the command, never the missing recipe's or rig's error.
TEST(CommandArgs, EnginesRefuseInvalidArgsFirst) {
  std::ostringstream out, err;
  const CommandIo io{out, err};
  PlanArgs plan;
  plan.recipe = "/nonexistent/recipe.yaml";
  plan.show_poses = -7;
  try {
    RunPlan(plan, io);
    ADD_FAILURE() << "plan ran";
  } catch (const UsageError& error) {
    EXPECT_NE(std::string(error.what()).find("irdist plan: --poses -7"), std::string::npos)
        << error.what();
  }
  SimArgs sim;
  sim.rig = "/nonexistent/rig.yaml";
  sim.time_scale = 1.0e6;
  EXPECT_THROW(RunSim(sim, io), UsageError);
  SnapArgs snap;
  snap.rig = "/nonexistent/rig.yaml";
  snap.exposure_ms = kNan;
  EXPECT_THROW(RunSnap(snap, io), UsageError);
  StationTestArgs board;
  board.port = "/nonexistent/tty";
  board.baud = -1;
  EXPECT_THROW(RunStationTest(board, io), UsageError);
}

}  // namespace
}  // namespace irdist
