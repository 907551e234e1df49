#include "estimator/fit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "base/check.h"

namespace irdist {
namespace {

constexpr double kDeg = M_PI / 180.0;

// A geometric model with a blur varying with distance: alpha 30 px^2 at 1 m,
// b(u) = 0.6 - 0.5 u + 0.9 u^2.
GeometricModel Geometric() {
  GeometricModel g;
  g.alpha_px2 = 30.0;
  g.beta_px2 = 0.6;
  g.blur_u1_px2 = -0.5;
  g.blur_u2_px2 = 0.9;
  return g;
}

double ZOf(double d_mm) { return (d_mm - 2250.0) / 750.0; }  // 1.5..3 m onto [-1, 1]

// The moment variances of a disc at d_mm tilted by theta whose blur-free axis ratio squared reads
// x = gain cos^2(theta) + offset + slope z (a threshold cut's pose-dependent bias).
Features Frame(double d_mm, double theta_deg, double gain = 1.0, double offset = 0.0,
               double slope = 0.0) {
  const GeometricModel g = Geometric();
  const double c = std::cos(theta_deg * kDeg);
  const double x = gain * c * c + offset + slope * ZOf(d_mm);
  const double disc = g.alpha_px2 * 1e6 / (d_mm * d_mm);
  Features f;
  f.blob_found = true;
  f.moment_major_var_px2 = disc + g.BlurVarPx2(d_mm);
  f.moment_minor_var_px2 = x * disc + g.BlurVarPx2(d_mm);
  return f;
}

std::vector<CalibrationSample> Grid(double gain, double offset, double slope) {
  std::vector<CalibrationSample> out;
  for (double d : {1500.0, 2000.0, 2500.0, 3000.0}) {
    for (double theta : {0.0, 10.0, 20.0, 30.0, 40.0}) {
      CalibrationSample s;
      s.d_mm = d;
      s.theta_deg = theta;
      s.measurement = Frame(d, theta, gain, offset, slope);
      out.push_back(s);
    }
  }
  return out;
}

// Without a correction, theta is acos of the axis ratio with b(u) removed at the geometric
// distance: a disc at 60 deg shows minor / major = 1/2.
TEST(ThetaCorrection, UnfittedIsTheBlurCorrectedAxisRatio) {
  const GeometricModel g = Geometric();
  const Features f = Frame(2000.0, 60.0);
  EXPECT_NEAR(ThetaCorrection().ThetaDeg(f.moment_major_var_px2, f.moment_minor_var_px2, g), 60.0,
              1e-9);
  const Features round = Frame(2500.0, 0.0);
  EXPECT_NEAR(ThetaCorrection().ThetaDeg(round.moment_major_var_px2, round.moment_minor_var_px2, g),
              0.0, 1e-6);
  // No blob beyond the blur, or no geometric model: no theta.
  EXPECT_TRUE(std::isnan(ThetaCorrection().ThetaDeg(0.5, 0.5, g)));
  EXPECT_TRUE(std::isnan(ThetaCorrection().ThetaDeg(8.0, 4.0, GeometricModel())));
}

// A hand-made degree 2 correction, cos^2 = 0.02 + 0.9 x + 0.01 z + 0.05 x^2 (graded order:
// 1, x, z, x^2, x z, z^2); x and z clamped to the calibrated ranges.
TEST(ThetaCorrection, EvaluatesItsPolynomialInGradedOrder) {
  const GeometricModel g = Geometric();
  ThetaCorrection tc;
  tc.degree = 2;
  tc.coefficients = {0.02, 0.9, 0.01, 0.05, 0.0, 0.0};
  tc.ratio_sq_min = 0.5;
  tc.ratio_sq_max = 0.95;
  tc.d_min_mm = 1500.0;
  tc.d_max_mm = 3000.0;
  const auto expected = [](double x, double z) {
    return std::acos(std::sqrt(0.02 + 0.9 * x + 0.01 * z + 0.05 * x * x)) / kDeg;
  };
  const double c30 = std::cos(30.0 * kDeg);
  const Features f = Frame(2000.0, 30.0);  // x = cos^2(30 deg) = 0.75, z = -1/3
  EXPECT_NEAR(tc.ThetaDeg(f.moment_major_var_px2, f.moment_minor_var_px2, g),
              expected(c30 * c30, ZOf(2000.0)), 1e-9);
  const Features far = Frame(5000.0, 30.0);  // beyond the range: read at 3 m (z = 1)
  EXPECT_NEAR(tc.ThetaDeg(far.moment_major_var_px2, far.moment_minor_var_px2, g),
              expected(c30 * c30, 1.0), 1e-9);
  const Features round = Frame(2000.0, 0.0);  // x = 1: read at the calibrated 0.95
  EXPECT_NEAR(tc.ThetaDeg(round.moment_major_var_px2, round.moment_minor_var_px2, g),
              expected(0.95, ZOf(2000.0)), 1e-9);
  // cos^2 above 1 is clamped: theta 0, not NaN.
  tc.coefficients = {0.5, 1.0, 0.0, 0.0, 0.0, 0.0};
  EXPECT_EQ(tc.ThetaDeg(f.moment_major_var_px2, f.moment_minor_var_px2, g), 0.0);
}

TEST(ThetaCorrection, RefusesCoefficientsNotMatchingItsDegree) {
  ThetaCorrection tc;
  tc.degree = 2;
  tc.coefficients = {0.0, 1.0, 0.0};  // degree 1's count
  tc.d_max_mm = 3000.0;
  const Features f = Frame(2000.0, 30.0);
  try {
    tc.ThetaDeg(f.moment_major_var_px2, f.moment_minor_var_px2, Geometric());
    FAIL() << "a degree 2 correction with 3 coefficients was evaluated";
  } catch (const CheckError& e) {
    EXPECT_NE(std::string(e.what()).find("needs 6 coefficients, has 3"), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(ThetaCorrection::NumTerms(1), 3);
  EXPECT_EQ(ThetaCorrection::NumTerms(2), 6);
  EXPECT_EQ(ThetaCorrection::NumTerms(3), 10);
}

// Frames whose x = 0.9 cos^2 + 0.05 + 0.02 z: the degree 1 fit is the exact inverse,
// cos^2 = (x - 0.05 - 0.02 z) / 0.9, and its residuals vanish; ranges are those of the frames.
TEST(FitThetaCorrection, RecoversALinearBiasExactly) {
  const std::vector<CalibrationSample> samples = Grid(0.9, 0.05, 0.02);
  const ThetaCorrection tc = FitThetaCorrection(samples, Geometric(), 1);
  ASSERT_TRUE(tc.fitted()) << tc.summary.message;
  ASSERT_EQ(tc.coefficients.size(), 3u);
  EXPECT_NEAR(tc.coefficients[0], -0.05 / 0.9, 1e-9);
  EXPECT_NEAR(tc.coefficients[1], 1.0 / 0.9, 1e-9);
  EXPECT_NEAR(tc.coefficients[2], -0.02 / 0.9, 1e-9);
  EXPECT_NEAR(tc.d_min_mm, 1500.0, 1e-6);
  EXPECT_NEAR(tc.d_max_mm, 3000.0, 1e-6);
  const double c40 = std::cos(40.0 * kDeg);
  EXPECT_NEAR(tc.ratio_sq_min, 0.9 * c40 * c40 + 0.05 - 0.02, 1e-12);
  EXPECT_NEAR(tc.ratio_sq_max, std::min(1.0, 0.9 + 0.05 + 0.02), 1e-12);
  EXPECT_EQ(tc.summary.samples, 20);
  EXPECT_EQ(tc.summary.residuals.size(), 20u);
  // Theta at 10 deg and up is exact; nearly round blobs (0 deg) to the clamped ratio's precision.
  EXPECT_LT(tc.summary.max_relative_error, 1e-4);  // degrees
  EXPECT_EQ(tc.summary.termination, FitSummary::Termination::kConverged);
}

// Unusable frames (saturated) are not fitted; too few usable frames (2x the terms), no geometric
// model, or one angle at one distance (rank-deficient) give no correction, with the reason.
TEST(FitThetaCorrection, SaysWhyItDidNotFit) {
  std::vector<CalibrationSample> samples = Grid(1.0, 0.0, 0.0);
  for (size_t i = 0; i < samples.size(); i += 2) samples[i].measurement.saturated_pixels = 3;
  const ThetaCorrection ten = FitThetaCorrection(samples, Geometric(), 1);
  EXPECT_TRUE(ten.fitted());
  EXPECT_EQ(ten.summary.samples, 10);
  const ThetaCorrection too_few = FitThetaCorrection(samples, Geometric(), 3);  // needs 20
  EXPECT_FALSE(too_few.fitted());
  EXPECT_EQ(too_few.summary.message, "too few usable frames for the theta correction");

  const ThetaCorrection no_geometry = FitThetaCorrection(Grid(1.0, 0.0, 0.0), GeometricModel(), 1);
  EXPECT_FALSE(no_geometry.fitted());
  EXPECT_NE(no_geometry.summary.message.find("no geometric model"), std::string::npos);

  std::vector<CalibrationSample> one_pose(8);
  for (CalibrationSample& s : one_pose) {
    s.d_mm = 2000.0;
    s.theta_deg = 20.0;
    s.measurement = Frame(2000.0, 20.0);
  }
  const ThetaCorrection flat = FitThetaCorrection(one_pose, Geometric(), 1);
  EXPECT_FALSE(flat.fitted());
  EXPECT_EQ(flat.degree, 0);
  EXPECT_NE(flat.summary.message.find("rank-deficient"), std::string::npos) << flat.summary.message;
}

TEST(FitThetaCorrection, RefusesADegreeOutsideOneToThree) {
  for (int degree : {0, 4}) {
    try {
      FitThetaCorrection(Grid(1.0, 0.0, 0.0), Geometric(), degree);
      ADD_FAILURE() << "degree " << degree << " accepted";
    } catch (const CheckError& e) {
      EXPECT_NE(std::string(e.what()).find("not in [1, 3]"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace irdist
