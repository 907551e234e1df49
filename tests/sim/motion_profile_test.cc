// One axis's trapezoidal (or triangular) motion in simulated time (sim/motion_profile.h): its
// phases' durations, its position and velocity at any instant, at rest before and after.
#include "sim/motion_profile.h"

#include <gtest/gtest.h>

#include <cmath>

namespace irdist::sim {
namespace {

// 100 mm at 50 mm/s, 100 mm/s^2: 0.5 s accelerating (12.5 mm), 1.5 s cruising (75 mm), 0.5 s
// decelerating (12.5 mm).
TEST(MotionProfile, TrapezoidReachesCruiseSpeedAndEndsAtRestOnTarget) {
  const MotionProfile p = MotionProfile::Make(0.0, 100.0, 10.0, 0.0, 50.0, 100.0);
  EXPECT_DOUBLE_EQ(p.vp, 50.0);
  EXPECT_DOUBLE_EQ(p.t_acc, 0.5);
  EXPECT_DOUBLE_EQ(p.t_cruise, 1.5);
  EXPECT_DOUBLE_EQ(p.t_dec, 0.5);
  EXPECT_DOUBLE_EQ(p.EndS(), 12.5);
  EXPECT_DOUBLE_EQ(p.PositionAt(9.0), 0.0);  // before the start: where it was
  EXPECT_DOUBLE_EQ(p.VelocityAt(9.0), 0.0);
  EXPECT_NEAR(p.PositionAt(10.5), 12.5, 1e-12);  // end of the acceleration
  EXPECT_NEAR(p.PositionAt(11.0), 37.5, 1e-12);  // cruising
  EXPECT_NEAR(p.VelocityAt(11.0), 50.0, 1e-12);
  EXPECT_NEAR(p.PositionAt(12.25), 100.0 - 0.5 * 100.0 * 0.25 * 0.25, 1e-12);  // decelerating
  EXPECT_NEAR(p.VelocityAt(12.25), 25.0, 1e-12);
  EXPECT_DOUBLE_EQ(p.PositionAt(20.0), 100.0);
  EXPECT_DOUBLE_EQ(p.VelocityAt(20.0), 0.0);
}

// A short move never reaches vmax: the peak speed is sqrt(a d) and the time 2 sqrt(d / a).
TEST(MotionProfile, ShortMoveIsATriangle) {
  const MotionProfile p = MotionProfile::Make(0.0, 4.0, 0.0, 0.0, 50.0, 100.0);
  EXPECT_NEAR(p.vp, 20.0, 1e-12);
  EXPECT_DOUBLE_EQ(p.t_cruise, 0.0);
  EXPECT_NEAR(p.Duration(), 0.4, 1e-12);
  EXPECT_NEAR(p.PositionAt(0.2), 2.0, 1e-12);  // half way at the peak
}

// Moving backwards: the velocity is negative, the position falls, and it stops on target.
TEST(MotionProfile, BackwardMoveHasNegativeVelocity) {
  const MotionProfile p = MotionProfile::Make(30.0, -10.0, 0.0, 0.0, 10.0, 20.0);
  EXPECT_LT(p.VelocityAt(1.0), 0.0);
  EXPECT_LT(p.PositionAt(1.0), 30.0);
  EXPECT_DOUBLE_EQ(p.PositionAt(p.EndS() + 1.0), -10.0);
}

// A start at speed v0 accelerates from it; a v0 that could not stop in the distance is cut to
// the speed that can (sqrt(2 a d)).
TEST(MotionProfile, InitialSpeedIsKeptOrCutToOneThatCanStop) {
  const MotionProfile p = MotionProfile::Make(0.0, 100.0, 0.0, 20.0, 50.0, 100.0);
  EXPECT_DOUBLE_EQ(p.v0, 20.0);
  EXPECT_NEAR(p.VelocityAt(1e-9), 20.0, 1e-6);
  EXPECT_NEAR(p.t_acc, 0.3, 1e-12);
  const MotionProfile fast = MotionProfile::Make(0.0, 2.0, 0.0, 1000.0, 50.0, 100.0);
  EXPECT_NEAR(fast.v0, 20.0, 1e-12);  // sqrt(2 * 100 * 2)
  EXPECT_DOUBLE_EQ(fast.PositionAt(fast.EndS()), 2.0);
}

TEST(MotionProfile, RestStaysPut) {
  const MotionProfile p = MotionProfile::Rest(7.0, 3.0);
  EXPECT_DOUBLE_EQ(p.Duration(), 0.0);
  EXPECT_DOUBLE_EQ(p.PositionAt(0.0), 7.0);
  EXPECT_DOUBLE_EQ(p.PositionAt(100.0), 7.0);
  EXPECT_DOUBLE_EQ(p.VelocityAt(100.0), 0.0);
  const MotionProfile none = MotionProfile::Make(5.0, 5.0, 0.0, 3.0, 10.0, 10.0);
  EXPECT_DOUBLE_EQ(none.Duration(), 0.0);
  EXPECT_DOUBLE_EQ(none.PositionAt(1.0), 5.0);
}

}  // namespace
}  // namespace irdist::sim
