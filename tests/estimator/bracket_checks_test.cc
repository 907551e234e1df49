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
