#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "estimator/fit.h"

namespace irdist {
namespace {

// A disc whose image has a variance of alpha px^2 along its major axis at 1 m (alpha u^2 at
// u = 1000 mm / d: the image scales as 1/d), tilted by theta (its minor axis cos^2(theta) of
// that), plus a thin lens's blur variance b(u) = beta + b1 u + b2 u^2 on both axes.
struct Lens {
  double alpha = 30.0, beta = 0.6, b1 = -0.5, b2 = 0.9, b3 = 0.0;
  double Blur(double d_mm) const {
    const double u = 1000.0 / d_mm;
    return beta + b1 * u + b2 * u * u + b3 * u * u * u;
  }
};

CalibrationSample Sample(const Lens& lens, double d_mm, double theta_deg) {
  const double u = 1000.0 / d_mm;
  const double c = std::cos(theta_deg * M_PI / 180.0);
  CalibrationSample s;
  s.d_mm = d_mm;
  s.theta_deg = theta_deg;
  s.measurement.blob_found = true;
  s.measurement.moment_major_var_px2 = lens.alpha * u * u + lens.Blur(d_mm);
  s.measurement.moment_minor_var_px2 = lens.alpha * c * c * u * u + lens.Blur(d_mm);
  return s;
}

std::vector<CalibrationSample> Grid(const Lens& lens,
                                    const std::vector<double>& distances_mm = {
                                        1200.0, 1500.0, 2000.0, 2500.0, 3000.0, 4000.0}) {
  std::vector<CalibrationSample> out;
  for (double d : distances_mm) {
    for (double theta : {0.0, 20.0, 35.0}) out.push_back(Sample(lens, d, theta));
  }
  return out;
}

// The fixed blur: alpha and beta recovered exactly; the distances implied agree with the truth.
TEST(FitGeometric, FixedBlurRecoversTheSizeLaw) {
  Lens lens;
  lens.b1 = lens.b2 = 0.0;
  const GeometricModel g = FitGeometric(Grid(lens), false);
  ASSERT_TRUE(g.fitted());
  EXPECT_NEAR(g.alpha_px2, 30.0, 1e-9);
  EXPECT_NEAR(g.beta_px2, 0.6, 1e-9);
  EXPECT_EQ(g.blur_u1_px2, 0.0);
  EXPECT_EQ(g.blur_u2_px2, 0.0);
  EXPECT_FALSE(g.BlurVariesWithDistance());
  EXPECT_EQ(g.summary.termination, FitSummary::Termination::kConverged);
  EXPECT_EQ(g.summary.samples, 18);
  EXPECT_EQ(g.summary.residuals.size(), 18u);
  EXPECT_LT(g.summary.max_relative_error, 1e-12);
}

// A blur that varies with distance is separated from the disc by the minor axis (whose disc part
// shrinks with the tilt while the blur does not): all four coefficients come back. The fixed-blur
// fit of the same frames cannot follow it and misplaces distances.
TEST(FitGeometric, BlurQuadraticInInverseDistanceIsRecovered) {
  const Lens lens;
  const std::vector<CalibrationSample> samples = Grid(lens);
  const GeometricModel g = FitGeometric(samples, true);
  ASSERT_TRUE(g.fitted());
  EXPECT_NEAR(g.alpha_px2, 30.0, 1e-8);
  EXPECT_NEAR(g.beta_px2, 0.6, 1e-8);
  EXPECT_NEAR(g.blur_u1_px2, -0.5, 1e-8);
  EXPECT_NEAR(g.blur_u2_px2, 0.9, 1e-8);
  EXPECT_TRUE(g.BlurVariesWithDistance());
  EXPECT_LT(g.summary.max_relative_error, 1e-10);
  const GeometricModel fixed = FitGeometric(samples, false);
  EXPECT_GT(fixed.summary.max_relative_error, 1e-3);
}

// A size law that is not a quadratic in 1/d (a lens whose blob grows otherwise with distance):
// from 4 calibrated distances (Table 3's) the cubic term comes back and the law passes through
// every distance's sizes and the law between them; 3 distances keep the quadratic.
TEST(FitGeometric, FourDistancesFitTheSizeLawsCubicTerm) {
  Lens lens;
  lens.b3 = 0.4;
  const GeometricModel g = FitGeometric(Grid(lens, {1500.0, 2000.0, 2500.0, 3000.0}), true);
  ASSERT_TRUE(g.fitted());
  EXPECT_NEAR(g.alpha_px2, 30.0, 1e-7);
  EXPECT_NEAR(g.blur_u2_px2, 0.9, 1e-7);
  EXPECT_NEAR(g.blur_u3_px2, 0.4, 1e-7);
  EXPECT_LT(g.summary.max_relative_error, 1e-9);
  for (double d : {1700.0, 2300.0, 2900.0}) {
    EXPECT_NEAR(g.DistanceMm(lens.alpha * 1e6 / (d * d) + lens.Blur(d)), d, 1e-6 * d) << d;
  }
  const GeometricModel three = FitGeometric(Grid(lens, {1500.0, 2000.0, 2500.0}), true);
  ASSERT_TRUE(three.fitted());
  EXPECT_EQ(three.blur_u3_px2, 0.0);
  // Through its own 3 distances, the quadratic cannot follow the law between them.
  EXPECT_GT(std::fabs(three.DistanceMm(lens.alpha * 1e6 / (1700.0 * 1700.0) + lens.Blur(1700.0)) /
                          1700.0 -
                      1.0),
            1e-5);
}

// Frames with noise (relative sd 0.02% on each axis, fixed seed) at Table 3's 4 distances.
std::vector<CalibrationSample> NoisyTable3(const Lens& lens) {
  std::mt19937 rng(17);
  std::normal_distribution<double> noise(0.0, 2e-4);
  std::vector<CalibrationSample> out;
  for (int repeat = 0; repeat < 8; ++repeat) {
    for (CalibrationSample s : Grid(lens, {1500.0, 2000.0, 2500.0, 3000.0})) {
      s.measurement.moment_major_var_px2 *= 1.0 + noise(rng);
      s.measurement.moment_minor_var_px2 *= 1.0 + noise(rng);
      out.push_back(s);
    }
  }
  return out;
}

// From 4 distances on the cubic term is taken, whatever the lens: one 4 u^3 px^2 outside the
// quadratic's family gets it back within 10%; one of the family gets a term within its noise,
// whose distances between the calibrated ones stay within the frames' noise of the truth.
TEST(FitGeometric, TheCubicTermFromFourDistances) {
  Lens lens;
  const GeometricModel in_family = FitGeometric(NoisyTable3(lens), true);
  ASSERT_TRUE(in_family.fitted());
  EXPECT_NE(in_family.summary.message.find("cubic"), std::string::npos);
  EXPECT_LT(std::fabs(in_family.blur_u3_px2), 0.4) << in_family.summary.message;
  for (double d : {1700.0, 2300.0, 2900.0}) {
    const double var = lens.alpha * 1e6 / (d * d) + lens.Blur(d);
    EXPECT_NEAR(in_family.DistanceMm(var) / d - 1.0, 0.0, 2e-4) << d;
  }
  lens.b3 = 4.0;
  const GeometricModel outside = FitGeometric(NoisyTable3(lens), true);
  EXPECT_NEAR(outside.blur_u3_px2, 4.0, 0.4) << outside.summary.message;
}

// The model's own relations by hand: b(u), the expected variance and its inverse.
TEST(GeometricModel, DistanceInvertsTheExpectedVariance) {
  GeometricModel g;
  g.alpha_px2 = 30.0;
  g.beta_px2 = 1.0;
  // Fixed blur: var 8.5 = 30 u^2 + 1 at u = 0.5, 2 m.
  EXPECT_NEAR(g.DistanceMm(8.5), 2000.0, 1e-9);
  EXPECT_NEAR(g.MajorVarPx2(2000.0), 8.5, 1e-12);
  // Thin lens: b(0.5) = 0.6 - 0.25 + 0.225 = 0.575 px^2; var at 2 m = 7.5 + 0.575.
  g.beta_px2 = 0.6;
  g.blur_u1_px2 = -0.5;
  g.blur_u2_px2 = 0.9;
  EXPECT_NEAR(g.BlurVarPx2(2000.0), 0.575, 1e-12);
  EXPECT_NEAR(g.MajorVarPx2(2000.0), 8.075, 1e-12);
  for (double d : {800.0, 1500.0, 2000.0, 5000.0}) {
    EXPECT_NEAR(g.DistanceMm(g.MajorVarPx2(d)), d, 1e-9 * d) << d;
  }
  // With b1 > 0 too (the root written without cancellation).
  g.blur_u1_px2 = 0.5;
  EXPECT_NEAR(g.DistanceMm(g.MajorVarPx2(3000.0)), 3000.0, 1e-9);
  // With a cubic term, of either sign: the root where the law rises.
  for (double b3 : {0.4, -0.4}) {
    g.blur_u3_px2 = b3;
    EXPECT_NEAR(g.BlurVarPx2(2000.0), 0.6 + 0.25 + 0.225 + b3 * 0.125, 1e-12);
    for (double d : {800.0, 1500.0, 2000.0, 5000.0}) {
      EXPECT_NEAR(g.DistanceMm(g.MajorVarPx2(d)), d, 1e-9 * d) << d << " b3 " << b3;
    }
  }
}

TEST(GeometricModel, NoDistanceWhereTheVarianceHasNone) {
  GeometricModel g;
  g.alpha_px2 = 30.0;
  g.beta_px2 = 1.0;
  EXPECT_TRUE(std::isnan(g.DistanceMm(0.5)));  // below the blur: farther than infinity
  EXPECT_TRUE(std::isnan(g.DistanceMm(1.0)));  // the blur alone: u = 0
  EXPECT_TRUE(std::isnan(GeometricModel().DistanceMm(8.5)));  // no scale fitted
  EXPECT_FALSE(GeometricModel().fitted());
}

// The standard error through the slope: half the distances at var -+ se, here
// d(v) = 1000 sqrt(alpha / (v - beta)); about d / (2 (v - beta)) per px^2 to first order.
TEST(GeometricModel, DistanceStandardErrorFollowsTheSlope) {
  GeometricModel g;
  g.alpha_px2 = 30.0;
  g.beta_px2 = 1.0;
  const auto d = [](double v) { return 1000.0 * std::sqrt(30.0 / (v - 1.0)); };
  EXPECT_NEAR(g.DistanceSeMm(8.5, 0.5), 0.5 * (d(8.0) - d(9.0)), 1e-9);
  EXPECT_NEAR(g.DistanceSeMm(8.5, 0.01), 2000.0 / (2.0 * 7.5) * 0.01, 1e-3);
  EXPECT_TRUE(std::isnan(g.DistanceSeMm(1.2, 0.5)));  // var - se below the blur
}

// Frames without a blob or without a size are left out; fewer than 3 left is no fit, said so.
TEST(FitGeometric, NeedsThreeFramesWithABlob) {
  const Lens lens;
  std::vector<CalibrationSample> samples = {Sample(lens, 1500.0, 0.0), Sample(lens, 2000.0, 0.0),
                                            Sample(lens, 2500.0, 0.0), Sample(lens, 3000.0, 0.0)};
  samples[1].measurement.blob_found = false;
  samples[2].measurement.moment_major_var_px2 = 0.0;
  const GeometricModel g = FitGeometric(samples, false);
  EXPECT_FALSE(g.fitted());
  EXPECT_EQ(g.summary.samples, 2);
  EXPECT_NE(g.summary.message.find("fewer than 3 samples with a blob"), std::string::npos)
      << g.summary.message;
  EXPECT_NE(g.summary.termination, FitSummary::Termination::kConverged);
  EXPECT_TRUE(std::isnan(g.DistanceMm(8.0)));
}

}  // namespace
}  // namespace irdist
