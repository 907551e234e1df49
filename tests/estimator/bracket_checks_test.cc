// The checks of a bracket's estimate (estimator/bracket_checks.h): motion inside the bracket and
// the calibrated ranges.
#include "estimator/bracket_checks.h"

#include <gtest/gtest.h>

#include <cmath>

#include "base/check.h"

namespace irdist {
namespace {

// Motion: per-exposure distances within their noise of the joint one are static; a bracket whose
// exposures spread far beyond their standard errors (an IRED moving 200 mm/s over a 150 ms
// bracket: 30 mm against 1 mm) is moving, with its spread.
TEST(CheckMotion, FlagsASpreadBeyondTheNoiseOnly) {
  const std::vector<double> se = {1.0, 1.0, 1.0, 1.0};
  const MotionCheck still = CheckMotion(2000.0, {2000.5, 1999.2, 2000.9, 1999.6}, se);
  ASSERT_TRUE(still.assessed);
  EXPECT_EQ(still.exposures, 4);
  EXPECT_NEAR(still.chi2, 0.25 + 0.64 + 0.81 + 0.16, 1e-9);
  EXPECT_NEAR(still.chi2_limit, 16.266, 1e-3);  // chi-square, 3 dof, 0.999
  EXPECT_FALSE(still.moving);
  EXPECT_NEAR(still.spread_mm, 1.7, 1e-9);
  const MotionCheck moving = CheckMotion(2015.0, {2000.0, 2010.0, 2020.0, 2030.0}, se);
  EXPECT_TRUE(moving.moving);
  EXPECT_NEAR(moving.spread_mm, 30.0, 1e-9);
  // The same spread with 20 mm standard errors is noise.
  EXPECT_FALSE(CheckMotion(2015.0, {2000.0, 2010.0, 2020.0, 2030.0}, {20, 20, 20, 20}).moving);
}

TEST(CheckMotion, NeedsTwoExposuresWithStandardErrors) {
  EXPECT_FALSE(CheckMotion(2000.0, {2000.0}, {1.0}).assessed);
  // Exposures without a standard error (the paper's method: -1) are left out.
  EXPECT_FALSE(CheckMotion(2000.0, {1900.0, 2100.0}, {-1.0, 1.0}).assessed);
  EXPECT_FALSE(CheckMotion(NAN, {1900.0, 2100.0}, {1.0, 1.0}).assessed);
  EXPECT_THROW(CheckMotion(2000.0, {1.0}, {}), CheckError);
}

// A geometric model with no blur: major var = alpha (1000 / d)^2, alpha 60 px^2 (15 px^2 at 2 m,
// a disc of 7.7 px semi-axis).
GeometricModel NoBlurGeometric() {
  GeometricModel g;
  g.alpha_px2 = 60.0;
  return g;
}

// A frame as the blob fit leaves it: a disc whose major-axis variance is `major` and whose trace
// size (harmonic mean of the axes' variances) is `trace`, with the trace's standard error `se`.
Features SizedFrame(double major, double trace, double se) {
  Features f;
  f.blob_found = true;
  f.moment_major_var_px2 = major;
  f.trace_var_px2 = trace;
  f.trace_var_se_px2 = se;
  return f;
}

// Motion from the frames' own sizes: four frames of a static IRED at 2 m (major var 15 px^2, a
// tilted disc's trace 12 px^2) scattered within their errors are static, with distances on the
// major axis (the bracket's ratio 15/12 puts each trace there); the same frames with the size
// shrinking as an IRED receding 10 mm a frame (0.5%) are moving, with the 30 mm spread the
// sizes imply; a frame without a trace size (the moments' path) leaves it unassessed.
TEST(CheckMotionOfSizes, JudgesTheFramesSizesAgainstTheirOwnErrors) {
  const GeometricModel g = NoBlurGeometric();
  const double se = 0.012;  // 0.1% of the size: 1 mm of distance at 2 m
  const double noise[4] = {0.8, -1.1, 0.4, -0.2};
  std::vector<Features> still, moving;
  for (int k = 0; k < 4; ++k) {
    still.push_back(SizedFrame(15.0, 12.0 + noise[k] * se, se));
    const double shrink = 1.0 / ((1.0 + 0.005 * k) * (1.0 + 0.005 * k));  // d grows 0.5% a frame
    moving.push_back(SizedFrame(15.0 * shrink, 12.0 * shrink, se));
  }
  const auto pointers = [](const std::vector<Features>& v) {
    std::vector<const Features*> p;
    for (const Features& f : v) p.push_back(&f);
    return p;
  };
  const MotionCheck s = CheckMotionOfSizes(g, pointers(still));
  ASSERT_TRUE(s.assessed);
  EXPECT_EQ(s.exposures, 4);
  EXPECT_FALSE(s.moving);
  // Each frame's distance error is half its relative size error: 1 mm per se at 2000 mm.
  EXPECT_NEAR(s.spread_mm, (1.1 + 0.8) * 1.0, 0.02);
  double mean = 0.0;
  for (double n : noise) mean += n / 4.0;
  double chi2 = 0.0;
  for (double n : noise) chi2 += (n - mean) * (n - mean);
  EXPECT_NEAR(s.chi2, chi2, 0.01);
  EXPECT_NEAR(s.chi2_limit, 16.266, 1e-3);  // 3 degrees of freedom
  const MotionCheck m = CheckMotionOfSizes(g, pointers(moving));
  ASSERT_TRUE(m.assessed);
  EXPECT_TRUE(m.moving);
  EXPECT_NEAR(m.spread_mm, 2000.0 * 0.015, 0.5);
  still[2].trace_var_se_px2 = NAN;
  EXPECT_FALSE(CheckMotionOfSizes(g, pointers(still)).assessed);
  EXPECT_FALSE(CheckMotionOfSizes(GeometricModel(), pointers(moving)).assessed);  // no model
}

CalibratedRanges Table3Ranges() {
  CalibratedRanges r;
  r.d_min_mm = 1500.0;
  r.d_max_mm = 3000.0;
  r.theta_min_deg = 0.0;
  r.theta_max_deg = 35.0;
  r.t_min_ms = 30.0;
  r.t_max_ms = 36.0;
  r.t_ref_min_ms = r.t_ref_max_ms = 8.0;
  r.peak_min = 0.2;
  r.peak_max = 0.9;
  return r;
}

// The calibration's own edge is inside: 1499.5 +- 1.0 mm on a 1500-3000 mm calibration.
TEST(OutsideRanges, EdgesAreTestedWithTheEstimatesOwnStandardError) {
  DistanceEstimate e;
  e.d_mm = 1499.5;
  e.d_std_mm = 1.0;
  e.theta_deg = 35.3;
  e.theta_std_deg = 0.2;
  const std::vector<double> t_ms = {30, 32, 34, 36};
  EXPECT_TRUE(OutsideRanges(Table3Ranges(), e, 8.0, t_ms, {}).empty());
  e.d_mm = 1490.0;  // 10 standard errors below
  EXPECT_EQ(OutsideRanges(Table3Ranges(), e, 8.0, t_ms, {}), std::vector<std::string>{"distance"});
  // ... within 3 of the calibration's own error (0.3% of 1490 mm = 4.5 mm, with the se 4.6 mm).
  RangeOptions calibrated;
  calibrated.calibration_rel_error = 0.003;
  EXPECT_TRUE(OutsideRanges(Table3Ranges(), e, 8.0, t_ms, {}, calibrated).empty());
  e.d_mm = 2000.0;
  e.theta_deg = 42.0;
  EXPECT_EQ(OutsideRanges(Table3Ranges(), e, 8.0, t_ms, {}), std::vector<std::string>{"theta"});
}

// Every exposure and the signal, each named.
TEST(OutsideRanges, NamesEachExposureAndTheSignal) {
  DistanceEstimate e;
  e.d_mm = 2000.0;
  e.d_std_mm = 1.0;
  e.theta_deg = 10.0;
  const CalibratedRanges r = Table3Ranges();
  EXPECT_EQ(OutsideRanges(r, e, 8.0, {4.0}, {}), std::vector<std::string>{"t_meas"});
  EXPECT_EQ(OutsideRanges(r, e, 8.0, {30.0, 33.0, 120.0}, {}),
            std::vector<std::string>{"t_meas"});
  EXPECT_EQ(OutsideRanges(r, e, 2.0, {30.0}, {}), std::vector<std::string>{"t_ref"});
  Features dim;
  dim.blob_found = true;
  dim.peak = 0.05;
  Features fine = dim;
  fine.peak = 0.5;
  EXPECT_TRUE(OutsideRanges(r, e, 8.0, {30.0}, {&fine}).empty());
  EXPECT_EQ(OutsideRanges(r, e, 8.0, {30.0}, {&fine, &dim}), std::vector<std::string>{"signal"});
  CalibratedRanges old = r;  // a model without ranges.peak: the signal is not checked
  old.peak_min = old.peak_max = 0.0;
  EXPECT_TRUE(OutsideRanges(old, e, 8.0, {30.0}, {&dim}).empty());
}


// The options refuse a bad field with its name; the checks refuse such options.
TEST(MotionOptions, RefusesAFalseAlarmOutsideZeroToOne) {
  std::string why;
  EXPECT_TRUE(MotionOptions().IsValid(&why)) << why;
  EXPECT_EQ(why, "");
  for (const double bad : {0.0, 1.0, -0.1, double(NAN)}) {
    MotionOptions options;
    options.false_alarm = bad;
    EXPECT_FALSE(options.IsValid(&why));
    EXPECT_NE(why.find("false_alarm"), std::string::npos) << why;
    EXPECT_THROW(CheckMotion(2000.0, {2000.0, 2001.0}, {1.0, 1.0}, options), CheckError);
  }
}

TEST(RangeOptions, RefusesEachBadFieldByName) {
  std::string why;
  EXPECT_TRUE(RangeOptions().IsValid(&why)) << why;
  RangeOptions z;
  z.z_limit = 0.0;
  RangeOptions calibration;
  calibration.calibration_rel_error = -0.01;
  RangeOptions exposure;
  exposure.exposure_tolerance = 0.0;
  RangeOptions signal;
  signal.signal_tolerance = NAN;
  const std::vector<std::pair<RangeOptions, std::string>> cases = {
      {z, "z_limit"}, {calibration, "calibration_rel_error"},
      {exposure, "exposure_tolerance"}, {signal, "signal_tolerance"}};
  DistanceEstimate e;
  e.d_mm = 2000.0;
  e.d_std_mm = 1.0;
  for (const auto& [options, field] : cases) {
    EXPECT_FALSE(options.IsValid(&why)) << field;
    EXPECT_EQ(why.rfind(field, 0), 0u) << why;
    EXPECT_THROW(OutsideRanges(Table3Ranges(), e, 8.0, {30.0}, {}, options), CheckError);
  }
}
}  // namespace
}  // namespace irdist
