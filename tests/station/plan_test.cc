#include "station/plan.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "base/check.h"
#include "base/pi.h"

namespace irdist {
namespace {

double Cos(double deg) { return std::cos(deg * kPi / 180.0); }

TEST(PlanTest, DefaultsAreValid) {
  std::string why;
  EXPECT_TRUE(SweepSpec().IsValid(&why)) << why;
  EXPECT_TRUE(BracketSpec().IsValid(&why)) << why;
  EXPECT_TRUE(SettleSpec().IsValid(&why)) << why;
  EXPECT_TRUE(MotionModel().IsValid(&why)) << why;
  EXPECT_TRUE(RandomDraws().IsValid(&why)) << why;
}

TEST(PlanTest, InvalidSpecsAreRefused) {
  std::string why;
  SweepSpec spec;
  spec.slide_mm.values.clear();
  EXPECT_FALSE(spec.IsValid(&why));
  EXPECT_NE(why.find("slide_mm"), std::string::npos) << why;
  EXPECT_THROW(MakePlan(spec, MotionModel()), CheckError);

  spec = SweepSpec();
  spec.order = {SweepAxis::kSlide, SweepAxis::kSlide, SweepAxis::kTilt, SweepAxis::kBias};
  EXPECT_FALSE(spec.IsValid(&why));

  BracketSpec bracket;
  bracket.t_meas_ms = {8.0};  // not longer than t_ref
  EXPECT_FALSE(bracket.IsValid(&why));
  bracket = BracketSpec();
  bracket.repeats = 0;
  EXPECT_FALSE(bracket.IsValid(&why));

  MotionModel motion;
  motion.pan.acceleration = 0.0;
  EXPECT_FALSE(motion.IsValid(&why));
  EXPECT_NE(why.find("pan"), std::string::npos);

  RandomDraws draws;
  draws.mean = 700.0;
  draws.max = 600.0;
  EXPECT_FALSE(draws.IsValid(&why));
}

TEST(PlanTest, TrapezoidMatchesHandComputedProfiles) {
  const AxisMotion slide{200.0, 400.0, 0.0};  // reaches cruise after v^2/a = 100 mm
  // Long move: accelerate 0.5 s (50 mm), cruise 400 mm at 200 mm/s (2 s), decelerate 0.5 s.
  EXPECT_NEAR(TrapezoidMoveS(500.0, slide), 0.5 + 2.0 + 0.5, 1e-12);
  // Short move: triangle, half the distance accelerating: 25 mm = a t^2 / 2 -> t = sqrt(0.125).
  EXPECT_NEAR(TrapezoidMoveS(50.0, slide), 2.0 * std::sqrt(0.125), 1e-12);
  // The two profiles meet at d = v^2/a: 0.5 s up, 0.5 s down.
  EXPECT_NEAR(TrapezoidMoveS(100.0, slide), 1.0, 1e-12);
  EXPECT_NEAR(TrapezoidMoveS(100.0 + 1e-9, slide), 1.0, 1e-9);
  EXPECT_EQ(TrapezoidMoveS(0.0, slide), 0.0);
  EXPECT_EQ(TrapezoidMoveS(-500.0, slide), TrapezoidMoveS(500.0, slide));
}

TEST(PlanTest, CountsFramesAndDifferences) {
  SweepSpec spec;
  spec.slide_mm.values = {1500, 2000, 2500, 3000};
  spec.angle_deg.values = {0, 5, 10, 15, 20, 25, 30, 35};
  spec.bias_ma.values = {475, 500};
  Plan plan = MakePlan(spec, MotionModel());
  EXPECT_EQ(plan.summary.pose_count, 64);
  EXPECT_EQ(plan.summary.frames_per_pose, 5);
  EXPECT_EQ(plan.summary.frame_count, 320);
  EXPECT_EQ(plan.summary.difference_count, 256);

  spec.bracket.retake_reference = true;
  spec.bracket.repeats = 3;
  plan = MakePlan(spec, MotionModel());
  EXPECT_EQ(plan.summary.pose_count, 64 * 3);
  EXPECT_EQ(plan.summary.frame_count, 64 * 3 * 8);
  EXPECT_EQ(plan.summary.difference_count, 64 * 3 * 4);
  const std::string report = plan.summary.BriefReport();
  EXPECT_NE(report.find("192 poses"), std::string::npos) << report;
  EXPECT_NE(report.find("1536 in all"), std::string::npos) << report;
  EXPECT_NE(report.find("768 differences"), std::string::npos) << report;
  EXPECT_NE(report.find("Physical bound"), std::string::npos) << report;
}

TEST(PlanTest, DeviceSpeedsReplaceTheModelsAxesAndMoveTheBound) {
  MotionModel model;
  const std::map<Axis, AxisSpeed> speeds = {{Axis::kSlide, {100.0, 200.0, 30.0, 1000.0}},
                                            {Axis::kPan, {50.0, 100.0, 0.0, 0.0}},
                                            {Axis::kTilt, {0.0, 0.0, 0.0, 0.0}}};  // unknown
  const MotionModel on_devices = WithDeviceSpeeds(model, speeds);
  EXPECT_DOUBLE_EQ(on_devices.slide.speed, 100.0);
  EXPECT_DOUBLE_EQ(on_devices.slide.acceleration, 200.0);
  EXPECT_DOUBLE_EQ(on_devices.slide.settle_ms, 30.0);
  EXPECT_DOUBLE_EQ(on_devices.pan.speed, 50.0);
  EXPECT_DOUBLE_EQ(on_devices.pan.settle_ms, 0.0);
  EXPECT_DOUBLE_EQ(on_devices.tilt.speed, model.tilt.speed);  // a zero speed is not a report
  EXPECT_DOUBLE_EQ(on_devices.readout_ms, model.readout_ms);

  SweepSpec spec;
  spec.slide_mm.values = {1500, 3000};
  spec.angle_deg.values = {0, 35};
  const double bound_s = MakePlan(spec, model).summary.physical_bound_s;
  const double slower_slide_s = MakePlan(spec, on_devices).summary.physical_bound_s;
  EXPECT_GT(slower_slide_s, bound_s);
}

TEST(PlanTest, SlowestAxisOutermostAndSerpentine) {
  SweepSpec spec;
  spec.slide_mm.values = {1000, 2000, 3000};
  spec.angle_deg.values = {0, 10, 20};
  spec.bias_ma.values = {450, 500};
  spec.order = {SweepAxis::kSlide, SweepAxis::kAngle, SweepAxis::kBias, SweepAxis::kTilt};
  const Plan plan = MakePlan(spec, MotionModel());
  ASSERT_EQ(plan.poses.size(), 18u);
  // Slide outermost and monotonic; the angle snakes (bias is not serpentine by default).
  const std::vector<double> angles = {0,  0, 10, 10, 20, 20, 20, 20, 10,
                                      10, 0, 0,  0,  0,  10, 10, 20, 20};
  for (size_t i = 0; i < plan.poses.size(); ++i) {
    const Pose& pose = plan.poses[i];
    EXPECT_EQ(pose.index, static_cast<int>(i));
    EXPECT_EQ(pose.slide_mm, spec.slide_mm.values[i / 6]) << i;
    EXPECT_EQ(pose.theta_deg, angles[i]) << i;
    EXPECT_EQ(pose.bias_ma, i % 2 == 0 ? 450.0 : 500.0) << i;
  }
  EXPECT_EQ(plan.summary.order,
            (std::vector<std::string>{"slide_mm", "theta_deg", "bias_ma", "tilt_deg"}));

  spec.serpentine.clear();
  const Plan raster = MakePlan(spec, MotionModel());
  for (size_t i = 0; i < raster.poses.size(); ++i) {
    EXPECT_EQ(raster.poses[i].theta_deg, spec.angle_deg.values[(i / 2) % 3]) << i;
  }
}

TEST(PlanTest, NestedSerpentineChangesOneAxisPerStep) {
  SweepSpec spec;
  spec.slide_mm.values = {1000, 1500, 2000};
  spec.angle_deg.values = {0, 10, 20, 30};
  spec.tilt_deg.values = {-5, 0, 5};
  spec.order = {SweepAxis::kAngle, SweepAxis::kTilt, SweepAxis::kSlide, SweepAxis::kBias};
  spec.angle_mode = AngleMode::kPan;
  const Plan plan = MakePlan(spec, MotionModel());
  ASSERT_EQ(plan.poses.size(), 36u);
  std::set<std::vector<double>> seen;
  for (size_t i = 0; i < plan.poses.size(); ++i) {
    const Pose& p = plan.poses[i];
    seen.insert({p.slide_mm, p.pan_deg, p.tilt_deg});
    if (i == 0) continue;
    const Pose& q = plan.poses[i - 1];
    const int changed =
        (p.slide_mm != q.slide_mm) + (p.pan_deg != q.pan_deg) + (p.tilt_deg != q.tilt_deg);
    EXPECT_EQ(changed, 1) << "pose " << i;
    // Only neighbouring values: the snake never jumps across the grid.
    EXPECT_LE(std::abs(p.slide_mm - q.slide_mm), 500.0) << i;
    EXPECT_LE(std::abs(p.tilt_deg - q.tilt_deg), 5.0) << i;
  }
  EXPECT_EQ(seen.size(), 36u);  // every grid point once
}

TEST(PlanTest, AutomaticOrderPutsTheCostliestAxisOutermost) {
  SweepSpec spec;
  spec.slide_mm.values = {1500, 2000, 2500, 3000};  // 500 mm steps: ~3 s each
  spec.angle_deg.values = {0, 5, 10};               // 5 deg steps: < 1 s
  spec.bias_ma.values = {475, 500};                 // 0.5 s current settle
  MotionModel motion;
  std::vector<SweepAxis> order = ChooseAxisOrder(spec, motion);
  ASSERT_EQ(order.size(), 4u);
  EXPECT_EQ(order[0], SweepAxis::kSlide);
  EXPECT_EQ(order[1], SweepAxis::kAngle);
  EXPECT_EQ(order[2], SweepAxis::kBias);
  EXPECT_EQ(order[3], SweepAxis::kTilt);  // single-valued: never changes

  // A long current settle makes the bias the costliest axis.
  spec.settle.after_current_ms = 60000.0;
  order = ChooseAxisOrder(spec, motion);
  EXPECT_EQ(order[0], SweepAxis::kBias);
  EXPECT_EQ(order[1], SweepAxis::kSlide);

  // Per-pose random draws always go innermost.
  spec.bias_ma.random = RandomDraws{500.0, 50.0, 10, 7, true, 0.0, 600.0};
  order = ChooseAxisOrder(spec, motion);
  EXPECT_EQ(order.back(), SweepAxis::kBias);
}

TEST(PlanTest, RandomDrawsAreSeededTruncatedAndPerPose) {
  SweepSpec spec;
  spec.slide_mm.values = {1700, 2300, 2900};
  spec.angle_deg.values = {10, 15, 20};
  spec.bias_ma.random = RandomDraws{500.0, 50.0, 10, 13, true, 0.0, 520.0};
  spec.order = {SweepAxis::kSlide, SweepAxis::kAngle, SweepAxis::kTilt, SweepAxis::kBias};
  const Plan a = MakePlan(spec, MotionModel());
  const Plan b = MakePlan(spec, MotionModel());
  ASSERT_EQ(a.poses.size(), 90u);
  std::set<double> currents;
  for (size_t i = 0; i < a.poses.size(); ++i) {
    EXPECT_EQ(a.poses[i].bias_ma, b.poses[i].bias_ma);  // same seed, same draws
    EXPECT_LE(a.poses[i].bias_ma, 520.0);               // truncated
    EXPECT_GE(a.poses[i].bias_ma, 0.0);
    currents.insert(a.poses[i].bias_ma);
  }
  EXPECT_EQ(currents.size(), 90u);  // a fresh set at each (slide, angle)

  spec.bias_ma.random->seed = 14;
  const Plan c = MakePlan(spec, MotionModel());
  EXPECT_NE(c.poses[0].bias_ma, a.poses[0].bias_ma);

  // One set for the whole sweep when per_pose is false.
  spec.bias_ma.random->per_pose = false;
  const Plan d = MakePlan(spec, MotionModel());
  for (size_t i = 10; i < d.poses.size(); ++i) {
    EXPECT_EQ(d.poses[i].bias_ma, d.poses[i % 10].bias_ma) << i;
  }

  // The draws follow the normal law they are asked for.
  SweepSpec many;
  many.bias_ma.random = RandomDraws{500.0, 50.0, 4000, 3, true, -1e300, 1e300};
  const Plan e = MakePlan(many, MotionModel());
  double sum = 0.0;
  double sum2 = 0.0;
  for (const Pose& p : e.poses) {
    sum += p.bias_ma;
    sum2 += p.bias_ma * p.bias_ma;
  }
  const double n = static_cast<double>(e.poses.size());
  const double mean = sum / n;
  const double sd = std::sqrt(sum2 / n - mean * mean);
  EXPECT_NEAR(mean, 500.0, 4.0 * 50.0 / std::sqrt(n));
  EXPECT_NEAR(sd, 50.0, 4.0);
}

TEST(PlanTest, ThetaIsRealisedByPanAtTheGivenTilt) {
  SweepSpec spec;
  spec.angle_deg.values = {-30, 30};
  spec.tilt_deg.values = {20};
  const Plan plan = MakePlan(spec, MotionModel());
  ASSERT_EQ(plan.poses.size(), 2u);
  for (const Pose& p : plan.poses) {
    EXPECT_NEAR(Cos(p.theta_deg), Cos(p.pan_deg) * Cos(p.tilt_deg), 1e-12);
    EXPECT_EQ(p.tilt_deg, 20.0);
    EXPECT_EQ(p.pan_deg < 0, p.theta_deg < 0);
  }
  EXPECT_NEAR(plan.poses[1].pan_deg, std::acos(Cos(30) / Cos(20)) * 180.0 / kPi, 1e-9);

  spec.tilt_deg.values = {0};
  const Plan flat = MakePlan(spec, MotionModel());
  EXPECT_NEAR(flat.poses[1].pan_deg, 30.0, 1e-9);

  spec.angle_mode = AngleMode::kPan;
  spec.angle_deg.values = {30};
  spec.tilt_deg.values = {20};
  const Plan pan = MakePlan(spec, MotionModel());
  EXPECT_NEAR(pan.poses[0].theta_deg, std::acos(Cos(30) * Cos(20)) * 180.0 / kPi, 1e-9);

  // theta below the tilt cannot be reached.
  spec.angle_mode = AngleMode::kTheta;
  spec.angle_deg.values = {10};
  EXPECT_THROW(MakePlan(spec, MotionModel()), CheckError);
}

TEST(PlanTest, RepeatsStayAtThePose) {
  SweepSpec spec;
  spec.angle_deg.values = {0, 10};
  spec.bracket.repeats = 3;
  spec.bracket.t_meas_ms = {35};
  const Plan plan = MakePlan(spec, MotionModel());
  ASSERT_EQ(plan.poses.size(), 6u);
  for (int i = 0; i < 6; ++i) {
    EXPECT_EQ(plan.poses[i].repeat, i % 3);
    EXPECT_EQ(plan.poses[i].theta_deg, i < 3 ? 0.0 : 10.0);
  }
  EXPECT_EQ(plan.summary.moves, 2);  // to the first pose, then one pan move
}

// The slide at 1000 and 1500 mm, the pan at 0 and 10 deg, one current (500 mA) and one bracket
// (8 ms reference, 30 ms measurement) per pose; 200 ms of settling after a move, 500 ms after a
// current change.
SweepSpec TwoByTwoSweep() {
  SweepSpec spec;
  spec.slide_mm.values = {1000, 1500};
  spec.angle_deg.values = {0, 10};
  spec.bias_ma.values = {500};
  spec.order = {SweepAxis::kSlide, SweepAxis::kAngle, SweepAxis::kTilt, SweepAxis::kBias};
  spec.bracket.t_ref_ms = 8.0;
  spec.bracket.t_meas_ms = {30.0};
  spec.settle.after_move_ms = 200.0;
  spec.settle.after_current_ms = 500.0;
  return spec;
}

// Round numbers for hand-computed trapezoids: the slide at 200 mm/s and 400 mm/s^2, settling in
// 100 ms, homed at 1000 mm; the pan and the tilt at 30 deg/s and 60 deg/s^2, settling in 50 ms;
// 25 ms of readout, 5 ms of overhead per frame and 20 ms per pose.
MotionModel HandComputableMotion() {
  MotionModel motion;
  motion.slide = {200.0, 400.0, 100.0, 1000.0};  // homing leaves the slide at the first pose
  motion.pan = {30.0, 60.0, 50.0};
  motion.tilt = {30.0, 60.0, 50.0};
  motion.readout_ms = 25.0;
  motion.frame_overhead_ms = 5.0;
  motion.pose_overhead_ms = 20.0;
  return motion;
}

TEST(PlanTest, DurationMatchesHandComputedTrapezoids) {
  const SweepSpec spec = TwoByTwoSweep();
  MotionModel motion = HandComputableMotion();
  const Plan plan = MakePlan(spec, motion);
  // Poses: (1000, 0) (1000, 10) (1500, 10) (1500, 0).
  ASSERT_EQ(plan.poses.size(), 4u);
  EXPECT_EQ(plan.poses[2].slide_mm, 1500.0);
  EXPECT_EQ(plan.poses[2].pan_deg, 10.0);
  const double pan_10 = 2.0 * std::sqrt(5.0 / 60.0 * 2.0);  // triangle: 10 deg < v^2/a = 15 deg
  const double slide_500 = 500.0 / 200.0 + 200.0 / 400.0;   // trapezoid: 3 s
  const PlanSummary& s = plan.summary;
  // The first pose (1000, 0) is where homing leaves the station: no move to it.
  EXPECT_NEAR(s.motion_s, slide_500 + 2.0 * pan_10, 1e-9);
  EXPECT_NEAR(s.station_settle_s, 0.050 + 0.100 + 0.050, 1e-9);
  EXPECT_NEAR(s.move_settle_s, 3 * 0.200, 1e-9);
  EXPECT_EQ(s.moves, 3);
  EXPECT_EQ(s.current_changes, 1);
  // The current is switched on at the first pose, which needs no move: its whole 500 ms count.
  EXPECT_NEAR(s.current_settle_s, 0.500, 1e-9);
  EXPECT_NEAR(s.exposure_s, 4 * (0.008 + 0.030), 1e-9);
  EXPECT_NEAR(s.readout_s, 4 * 2 * 0.025, 1e-9);
  EXPECT_NEAR(s.overhead_s, 4 * (2 * 0.005 + 0.020), 1e-9);
  EXPECT_NEAR(s.total_s,
              s.motion_s + s.station_settle_s + s.move_settle_s + s.current_settle_s +
                  s.exposure_s + s.readout_s + s.overhead_s,
              1e-9);
  EXPECT_NEAR(s.physical_bound_s,
              slide_500 + 2.0 * pan_10 + 0.200 + 4 * 0.038 + 4 * 0.050, 1e-9);

  // From a home elsewhere, the first move counts: 500 mm of slide to reach 1000 from 500.
  motion.slide.home = 500.0;
  const PlanSummary from_home = MakePlan(spec, motion).summary;
  EXPECT_NEAR(from_home.motion_s, s.motion_s + slide_500, 1e-9);
  EXPECT_EQ(from_home.moves, 4);
  motion.slide.home = 1000.0;
  EXPECT_LT(s.physical_bound_s, s.total_s);

  // A diagonal move: together it lasts as long as its slowest axis, sequentially the sum.
  SweepSpec diagonal;
  diagonal.slide_mm.values = {1000, 1500};
  diagonal.angle_deg.values = {0, 10};
  diagonal.serpentine.clear();
  diagonal.order = {SweepAxis::kSlide, SweepAxis::kAngle, SweepAxis::kTilt, SweepAxis::kBias};
  // Raster: (1000,0) (1000,10) (1500,0) (1500,10): the third move is diagonal.
  const Plan together = MakePlan(diagonal, motion);
  EXPECT_NEAR(together.summary.motion_s, pan_10 + slide_500 + pan_10, 1e-9);
  motion.axes_move_together = false;
  const Plan apart = MakePlan(diagonal, motion);
  EXPECT_NEAR(apart.summary.motion_s, pan_10 + (slide_500 + pan_10) + pan_10, 1e-9);
  EXPECT_NEAR(apart.summary.station_settle_s, 0.050 + 0.150 + 0.050, 1e-9);
}

TEST(PlanTest, CurrentChangesAreCounted) {
  SweepSpec spec;
  spec.bias_ma.values = {475, 500, 525};
  spec.angle_deg.values = {0, 10};
  spec.order = {SweepAxis::kAngle, SweepAxis::kBias, SweepAxis::kSlide, SweepAxis::kTilt};
  const Plan plan = MakePlan(spec, MotionModel());
  // 6 poses, the current changes at every pose but where the angle advances (525 -> 525 would
  // only happen with a serpentine bias; it is not one): 475 500 525 | 475 500 525.
  EXPECT_EQ(plan.summary.current_changes, 6);
  spec.serpentine.push_back(SweepAxis::kBias);  // 475 500 525 | 525 500 475
  spec.settle.after_move_ms = 200.0;
  spec.settle.after_current_ms = 500.0;
  const Plan snake = MakePlan(spec, MotionModel());
  EXPECT_EQ(snake.summary.current_changes, 5);
  // The first change overlaps the 5.5 s move from home (1000 to 2000 mm): it costs nothing; the
  // other four happen without a move and cost their whole 500 ms.
  EXPECT_NEAR(snake.summary.current_settle_s, 4 * 0.5, 1e-12);
}

TEST(PlanTest, FormatDurationReadsNaturally) {
  EXPECT_EQ(FormatDuration(12.34), "12.3 s");
  EXPECT_EQ(FormatDuration(245.2), "4m 05.2s");
  EXPECT_EQ(FormatDuration(3723.0), "1h 02m 03s");
}

TEST(PlanTest, FormatDurationNeverRoundsTheUnrepresentable) {
  EXPECT_EQ(FormatDuration(2e9), "over 1e9 s");
  EXPECT_EQ(FormatDuration(std::numeric_limits<double>::infinity()), "over 1e9 s");
  EXPECT_EQ(FormatDuration(std::nan("")), "over 1e9 s");
}

// sd 1e308, or a window 1e-7 wide, would redraw for ever: IsValid refuses them and says the
// largest sd that works, and MakePlan throws instead of spinning.
TEST(PlanSafety, RandomDrawsThatCannotMeetTheirWindowAreRefusedWithTheFix) {
  const RandomDraws huge{500.0, 1e308, 3, 1, true, 0.0, 600.0};
  const RandomDraws narrow{500.0, 50.0, 3, 1, true, 500.0, 500.0000001};
  for (const RandomDraws& draws : {huge, narrow}) {
    std::string why;
    EXPECT_FALSE(draws.IsValid(&why));
    EXPECT_NE(why.find("lower sd to at most"), std::string::npos) << why;
    SweepSpec spec;
    spec.bias_ma.random = draws;
    EXPECT_THROW(MakePlan(spec, MotionModel()), CheckError);
    // The suggested sd keeps at least the fraction asked for, and the plan is made.
    RandomDraws fixed = draws;
    fixed.sd = draws.LargestUsableSd();
    EXPECT_NEAR(fixed.AcceptedFraction(), RandomDraws::kMinAcceptedFraction, 1e-6);
    EXPECT_TRUE(fixed.IsValid(&why)) << why;
    spec.bias_ma.random = fixed;
    const Plan plan = MakePlan(spec, MotionModel());
    for (const Pose& p : plan.poses) {
      EXPECT_GE(p.bias_ma, draws.min);
      EXPECT_LE(p.bias_ma, draws.max);
    }
  }
}

// 50000 poses x 42951 frames is more than an int holds: refused before any pose is made.
TEST(PlanSafety, FrameCountsThatWouldOverflowAreRefused) {
  SweepSpec spec;
  spec.slide_mm.values.assign(50000, 2000.0);
  spec.bracket.t_meas_ms.assign(42950, 30.0);
  std::string why;
  EXPECT_FALSE(spec.IsValid(&why));
  EXPECT_NE(why.find("2.14755e+09 frames"), std::string::npos) << why;
  EXPECT_THROW(MakePlan(spec, MotionModel()), CheckError);
}

}  // namespace
}  // namespace irdist
