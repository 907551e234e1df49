// The calibrated blur (estimator/blur_model.h): the quadratic in u = 1000 mm / d and the noise
// law, recovered from points drawn around known ones.

#include "estimator/blur_model.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace irdist {
namespace {

// c0 + c1 u + c2 u^2 = 2 + 0.5 u + 3 u^2; per-frame sd 0.02 (d / 1 m)^0.5.
std::vector<BlurPoint> DrawPoints(int per_distance, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  std::vector<BlurPoint> points;
  for (const double d_mm : {1000.0, 1500.0, 2000.0, 3000.0, 4000.0}) {
    const double u = 1000.0 / d_mm;
    const double sd = 0.02 * std::sqrt(d_mm / 1000.0);
    for (int i = 0; i < per_distance; ++i) {
      points.push_back({d_mm, 2.0 + 0.5 * u + 3.0 * u * u + sd * unit(rng)});
    }
  }
  return points;
}

TEST(BlurModel, RecoversTheQuadraticAndTheNoiseLaw) {
  const BlurCalibration b = FitBlurCalibration(DrawPoints(400, 7));
  ASSERT_TRUE(b.fitted());
  EXPECT_EQ(b.frames, 2000);
  EXPECT_NEAR(b.c0_px2, 2.0, 0.01);
  EXPECT_NEAR(b.c1_px2, 0.5, 0.03);
  EXPECT_NEAR(b.c2_px2, 3.0, 0.03);
  EXPECT_NEAR(b.BlurVarPx2(2000.0), 2.0 + 0.25 + 0.75, 0.005);
  EXPECT_NEAR(b.noise_exponent, 0.5, 0.1);
  EXPECT_NEAR(b.NoisePx2(1000.0), 0.02, 0.002);
  EXPECT_NEAR(b.NoisePx2(4000.0), 0.04, 0.004);
}

TEST(BlurModel, FewerPointsThanNeededAreNotFitted) {
  std::vector<BlurPoint> points = DrawPoints(3, 1);  // 15 points
  points.resize(kMinBlurCalibrationFrames - 1);
  const BlurCalibration b = FitBlurCalibration(points);
  EXPECT_FALSE(b.fitted());
  EXPECT_EQ(b.frames, kMinBlurCalibrationFrames - 1);
  points = DrawPoints(3, 1);
  EXPECT_TRUE(FitBlurCalibration(points).fitted());
}

TEST(BlurModel, OneDistanceGivesAConstantNoise) {
  std::vector<BlurPoint> points;
  for (int i = 0; i < 20; ++i) points.push_back({2000.0, 3.0 + (i % 2 == 0 ? 0.01 : -0.01)});
  const BlurCalibration b = FitBlurCalibration(points);
  ASSERT_TRUE(b.fitted());
  EXPECT_EQ(b.noise_exponent, 0.0);
  EXPECT_NEAR(b.BlurVarPx2(2000.0), 3.0, 1e-9);
  EXPECT_NEAR(b.NoisePx2(2000.0), 0.01, 1e-6);
}

TEST(BlurModel, NoiseLawThroughTheGroupsRms) {
  double at_1m = -1.0, exponent = -1.0;
  EXPECT_FALSE(FitNoiseLaw({{0.0, 1.0, 2}}, &at_1m, &exponent));  // fewer than 3 residuals
  EXPECT_EQ(at_1m, -1.0);
  // rms 0.1 at 1 m and 0.4 at 4 m: sd = 0.1 (d / 1 m)^1.
  ASSERT_TRUE(FitNoiseLaw({{0.0, 0.01 * 5, 5}, {std::log(4.0), 0.16 * 5, 5}}, &at_1m, &exponent));
  EXPECT_NEAR(at_1m, 0.1, 1e-12);
  EXPECT_NEAR(exponent, 1.0, 1e-12);
}

}  // namespace
}  // namespace irdist
