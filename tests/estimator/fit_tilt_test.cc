#include "estimator/fit_tilt.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace irdist {
namespace {

constexpr double kAlpha = 57.0, kBlur = 0.6, kRelNoise = 2e-4;

// A lens whose blob fit reads the tilted disc's major axis `tilt(theta)` px^2 off the law (the
// departure a PSF outside the fit's family leaves), on Table 3's grid: 4 distances, theta 0..35
// step 5, 8 frames each, relative noise kRelNoise on both axes, as a blob fit's frames (the blur
// it added, the major axis's standard error).
template <typename Tilt>
std::vector<CalibrationSample> Table3(Tilt tilt, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, kRelNoise);
  std::vector<CalibrationSample> out;
  for (double d : {1500.0, 2000.0, 2500.0, 3000.0}) {
    for (double theta = 0.0; theta <= 35.0; theta += 5.0) {
      for (int repeat = 0; repeat < 8; ++repeat) {
        const double u = 1000.0 / d, c = std::cos(theta * M_PI / 180.0);
        CalibrationSample s;
        s.d_mm = d;
        s.theta_deg = theta;
        Features& f = s.measurement;
        f.blob_found = true;
        f.size_blur_var_px2 = kBlur;
        const double major = kAlpha * u * u + kBlur + tilt(theta);
        f.moment_major_var_px2 = major * (1.0 + noise(rng));
        f.moment_minor_var_px2 = (kAlpha * c * c * u * u + kBlur) * (1.0 + noise(rng));
        f.major_var_se_px2 = kRelNoise * major;
        out.push_back(s);
      }
    }
  }
  return out;
}

// An astigmatic lens's pattern (docs/estimator.md "The size's tilt term"): larger at 10-20 deg,
// smaller at 30-35.
double Astigmatic(double theta_deg) {
  return theta_deg >= 10.0 && theta_deg <= 20.0 ? 0.009 : theta_deg >= 30.0 ? -0.012 : 0.0;
}

// Each angle's mean relative distance error over its frames, under g (with or without its term).
std::vector<double> MeanErrorPerAngle(const GeometricModel& g,
                                      const std::vector<CalibrationSample>& samples) {
  std::vector<double> sum(8, 0.0);
  std::vector<int> n(8, 0);
  for (const CalibrationSample& s : samples) {
    const int k = static_cast<int>(std::lround(s.theta_deg / 5.0));
    sum[k] += g.DistanceMm(g.FrameMajorVarPx2(s.measurement)) / s.d_mm - 1.0;
    ++n[k];
  }
  for (int k = 0; k < 8; ++k) sum[k] /= n[k];
  return sum;
}

// The term comes back from the calibration's own poses, and with it no angle reads its distance
// off by more than the frames' noise; the law without it reads 10-20 deg short and 30-35 long.
TEST(FitTilt, TheSizesDependenceOnTiltIsMeasuredAndRemoved) {
  const std::vector<CalibrationSample> samples = Table3(Astigmatic, 5);
  const GeometricModel g = FitGeometric(samples, true);
  ASSERT_TRUE(g.fitted());
  ASSERT_EQ(g.tilt_theta_deg.size(), 8u) << g.summary.message;
  EXPECT_NE(g.summary.message.find("tilt term over 8 angles"), std::string::npos);
  // Up to the constant the law's beta takes: the pattern's steps.
  EXPECT_NEAR(g.TiltVarPx2(15.0) - g.TiltVarPx2(0.0), 0.009, 0.002);
  EXPECT_NEAR(g.TiltVarPx2(35.0) - g.TiltVarPx2(0.0), -0.012, 0.002);
  for (double e : MeanErrorPerAngle(g, samples)) EXPECT_LT(std::fabs(e), 4e-5);
  GeometricModel without = g;
  without.tilt_theta_deg.clear();
  without.tilt_var_px2.clear();
  const std::vector<double> before = MeanErrorPerAngle(without, samples);
  EXPECT_LT(before[3], -1e-4);  // 15 deg: the larger size reads short
  EXPECT_GT(before[7], 1e-4);   // 35 deg: the smaller one long
}

// A lens whose size does not depend on the tilt: each knot within its noise shrinks towards 0,
// and the term moves no angle's distance by more than the frames' noise.
TEST(FitTilt, NoTermBeyondTheNoiseWhereTheSizeDoesNotDependOnTilt) {
  for (unsigned seed : {1u, 2u, 3u}) {
    const GeometricModel g = FitGeometric(Table3([](double) { return 0.0; }, seed), true);
    ASSERT_TRUE(g.fitted());
    for (double t : g.tilt_var_px2) EXPECT_LT(std::fabs(t), 1.5e-3) << seed;
  }
}

// Where the term applies: a blob fit's frame at its own theta (the knots' values interpolated,
// the ends' beyond them); the moments' frames (no blob fit) as they are.
TEST(FitTilt, TheTermAppliesToTheBlobFitsFramesAtTheirOwnTheta) {
  GeometricModel g;
  g.tilt_theta_deg = {0.0, 10.0, 30.0};
  g.tilt_var_px2 = {0.0, 0.01, -0.02};
  EXPECT_NEAR(g.TiltVarPx2(5.0), 0.005, 1e-12);
  EXPECT_NEAR(g.TiltVarPx2(20.0), -0.005, 1e-12);
  EXPECT_NEAR(g.TiltVarPx2(45.0), -0.02, 1e-12);
  EXPECT_NEAR(g.TiltVarPx2(-20.0), -0.005, 1e-12);
  Features f;
  f.moment_major_var_px2 = 10.6;
  f.moment_minor_var_px2 = 10.0 * 0.75 + 0.6;  // cos^2(30 deg) of the disc's 10 px^2
  EXPECT_EQ(g.FrameMajorVarPx2(f), 10.6);      // moments: no blob fit
  f.size_blur_var_px2 = 0.6;
  EXPECT_NEAR(FrameDiscThetaDeg(f), 30.0, 1e-9);
  EXPECT_NEAR(g.FrameMajorVarPx2(f), 10.62, 1e-12);
  EXPECT_EQ(GeometricModel().FrameMajorVarPx2(f), 10.6);  // no term
}

}  // namespace
}  // namespace irdist
