#include "sim/trajectory.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "sim/station_model.h"
#include "sim/world.h"
#include "tests/sim/station_on_world.h"

// The station's trajectory as a function of time, from the station model's own profiles, checked
// against the trapezoid written out by hand: a slide move 1500 -> 3000 mm at 0.5 m/s, 1 m/s^2.

namespace irdist::sim {
namespace {

using testing::ExpectedSlideMm;
using testing::ExpectedSlideMmS;

class TrajectoryTest : public ::testing::Test {
 protected:
  TrajectoryTest() : effects_(world_), model_(effects_, testing::HalfMetrePerSecond()) {
    model_.PowerOn(0.0);
    Run("HOME", 0.0, 30.0);
    Run("MOVE 150000,0,0", 30.0, 40.0);
  }
  // Executes `command` at `at_s` and advances the model in 1 ms steps until `until_s`.
  void Run(const std::string& command, double at_s, double until_s) {
    ASSERT_EQ(model_.Execute(command, at_s), "OK") << command;
    for (double t = at_s; t < until_s; t += 0.001) model_.Advance(t);
  }

  World world_;
  testing::WorldEffects effects_;
  StationModel model_;
};

TEST_F(TrajectoryTest, SlideMoveFollowsItsProfileThroughStartCruiseAndStop) {
  const double t0 = 50.0;
  Run("MOVE 300000,0,0", t0, t0 + 5.0);
  for (double tau : {-1.0, 0.0, 0.1, 0.25, 0.5, 1.0, 2.0, 2.9, 3.0, 3.2, 3.4999, 3.5, 4.0}) {
    const TrajectoryPoint p = world_.TruthAt(t0 + tau);
    ASSERT_TRUE(p.known);
    EXPECT_NEAR(p.slide_mm, ExpectedSlideMm(tau), 1e-9) << "tau " << tau;
    EXPECT_NEAR(p.slide_mm_s, ExpectedSlideMmS(tau), 1e-9) << "tau " << tau;
    EXPECT_EQ(p.pan_deg, 0.0);
    EXPECT_EQ(p.tilt_deg, 0.0);
  }
  // Between the emulator's samples too: the pose is computed, not sampled.
  EXPECT_NEAR(world_.PoseAt(t0 + 1.0000004).slide_mm, 1875.0002, 1e-6);
}

TEST_F(TrajectoryTest, StopDeceleratesFromWhereTheAxisIsWithoutAJump) {
  const double t0 = 50.0;
  ASSERT_EQ(model_.Execute("MOVE 300000,3000,0", t0), "OK");
  for (double t = t0; t < t0 + 1.0; t += 0.001) model_.Advance(t);
  Run("STOP", t0 + 1.0, t0 + 3.0);
  const TrajectoryPoint before = world_.TruthAt(t0 + 1.0 - 1e-9);
  const TrajectoryPoint after = world_.TruthAt(t0 + 1.0);
  EXPECT_NEAR(after.slide_mm, before.slide_mm, 1e-5);
  EXPECT_NEAR(after.slide_mm_s, 500.0, 1e-9);
  EXPECT_NEAR(after.pan_deg, before.pan_deg, 1e-5);
  // Decelerating at 1 m/s^2 from 0.5 m/s: 125 mm further, at rest 0.5 s later.
  EXPECT_NEAR(world_.TruthAt(t0 + 1.5).slide_mm, ExpectedSlideMm(1.0) + 125.0, 1e-9);
  EXPECT_EQ(world_.TruthAt(t0 + 1.6).slide_mm_s, 0.0);
  EXPECT_GT(world_.TruthAt(t0 + 1.0).pan_deg_s, 0.0);
  EXPECT_NEAR(world_.TruthAt(t0 + 1.0).theta_deg, world_.TruthAt(t0 + 1.0).pan_deg, 1e-9);
}

TEST(TrajectoryAlone, HasNoTruthUntilEveryAxisHasAProfileAndMapsTimestampsToMidExposure) {
  Trajectory trajectory;
  EXPECT_FALSE(trajectory.At(1.0).known);
  trajectory.Add(RigAxis::kSlide, MotionProfile::Make(2000.0, 2100.0, 1.0, 0.0, 100.0, 1e6));
  EXPECT_FALSE(trajectory.At(1.0).known);
  trajectory.Add(RigAxis::kPan, MotionProfile::Rest(10.0, 0.0));
  trajectory.Add(RigAxis::kTilt, MotionProfile::Rest(0.0, 0.0));
  // Frame exposed from 1.5 s for 8 ms: its truth is at 1.504 s.
  const TrajectoryPoint mid = MidExposure(trajectory, SimTimeToNs(1.5), 8000.0);
  ASSERT_TRUE(mid.known);
  EXPECT_NEAR(mid.time_s, 1.504, 1e-12);
  // 100 mm/s cruise after a 0.1 ms ramp (0.005 mm behind): 2000 + 100 x 0.504 - 0.005.
  EXPECT_NEAR(mid.slide_mm, 2050.395, 1e-9);
  EXPECT_NEAR(mid.theta_deg, 10.0, 1e-12);
  EXPECT_EQ(SimTimeToNs(1.5), 1500000000u);
}

}  // namespace
}  // namespace irdist::sim
