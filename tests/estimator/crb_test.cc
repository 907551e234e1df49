// The Cramer-Rao bound's Fisher information (estimator/crb.h) against closed forms: a disc whose
// flux alone tells the distance (E = K / d^2), under pure Poisson noise and with read noise.
#include "estimator/crb.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace irdist {
namespace {

TEST(PixelNoise, DefaultsAreValid) {
  std::string why;
  EXPECT_TRUE(PixelNoise().IsValid(&why)) << why;
  PixelNoise bad;
  bad.read_noise_e = -1.0;
  EXPECT_FALSE(bad.IsValid(&why));
}

TEST(PixelNoise, VarianceIsShotPlusDarkPlusReadPlusQuantisation) {
  PixelNoise n;
  n.read_noise_e = 3.0;
  n.dark_e = 5.0;
  n.system_gain_dn_per_e = 0.5;  // 1/12 DN^2 = 1/3 e-^2
  EXPECT_NEAR(n.VarianceE2(100.0), 100.0 + 5.0 + 9.0 + 1.0 / 3.0, 1e-12);
}

// A uniformly bright disc of `pixels` pixels at distance d whose total signal is
// total_e (d_ref / d)^2: mu = total_e / pixels per pixel, d mu / d d = -2 mu / d, d mu / d ln I0 =
// mu; the disc's size and position are held fixed (their derivatives zero).
FrameSensitivity FluxDisc(double total_e, int pixels, double d_mm, double read_noise_e) {
  FrameSensitivity f;
  const double mu = total_e / pixels;
  f.expected_e = cv::Mat1d(1, pixels, mu);
  for (int k = 0; k < kNumCrbParams; ++k) f.derivatives[k] = cv::Mat1d::zeros(1, pixels);
  f.derivatives[kCrbLnI0] = f.expected_e.clone();
  f.derivatives[kCrbD] = cv::Mat1d(1, pixels, -2.0 * mu / d_mm);
  f.noise.read_noise_e = read_noise_e;
  return f;
}

// Pure Poisson: the Fisher information of d is sum (2 mu / d)^2 / mu = 4 N / d^2 for N photo-
// electrons in all, so sd(d) = d / (2 sqrt(N)), whatever their spread over pixels and frames.
TEST(FisherInformation, PoissonFluxGivesDistanceOverTwiceRootOfTheElectrons) {
  const double d_mm = 2700.0;
  for (double n_e : {1e4, 4e4, 1e6}) {
    FisherInformation info;
    info.AddFrame(FluxDisc(0.3 * n_e, 37, d_mm, 0.0));
    info.AddFrame(FluxDisc(0.7 * n_e, 52, d_mm, 0.0));  // a second exposure of the same disc
    const double sd_mm = std::sqrt(info.BoundVariance(kCrbD, {kCrbD}));
    EXPECT_NEAR(sd_mm, d_mm / (2.0 * std::sqrt(n_e)), 1e-9 * d_mm) << n_e;
  }
}

// Read noise r on every pixel: each pixel contributes (2 mu / d)^2 / (mu + r^2).
TEST(FisherInformation, ReadNoiseEntersAsAddedVariancePerPixel) {
  const double d_mm = 1500.0, total_e = 5e4, read_e = 7.0;
  const int pixels = 200;
  const double mu = total_e / pixels;
  FisherInformation info;
  info.AddFrame(FluxDisc(total_e, pixels, d_mm, read_e));
  const double expected_var = 1.0 / (pixels * (2.0 * mu / d_mm) * (2.0 * mu / d_mm) /
                                     (mu + read_e * read_e));
  EXPECT_NEAR(info.BoundVariance(kCrbD, {kCrbD}), expected_var, 1e-9 * expected_var);
}

// The flux alone cannot tell d from I0 (the paper's whole problem): with ln I0 free the
// information is singular, and the bound says so instead of returning a number.
TEST(FisherInformation, FluxAloneCannotSeparateDistanceFromIntensity) {
  FisherInformation info;
  info.AddFrame(FluxDisc(1e5, 50, 2000.0, 7.0));
  EXPECT_TRUE(std::isnan(info.BoundVariance(kCrbD, {kCrbLnI0, kCrbD})));
  const CrbResult r = ComputeFrameCrb({FluxDisc(1e5, 50, 2000.0, 7.0)}, false);
  EXPECT_FALSE(r.valid);
  EXPECT_NE(r.BriefReport().find("singular"), std::string::npos);
}

// A size cue separates them: pixels whose share of the flux depends on d (a disc shrinking as
// 1/d) break the degeneracy; adding a nuisance never lowers the bound.
TEST(FisherInformation, ANuisanceParameterNeverLowersTheBound) {
  FrameSensitivity f = FluxDisc(1e5, 50, 2000.0, 7.0);
  for (int i = 0; i < 50; ++i) {
    f.derivatives[kCrbD](0, i) *= (i < 25 ? 1.5 : 0.5);
    f.derivatives[kCrbX](0, i) = 30.0 * std::sin(0.3 * i);  // the blob's position cues
    f.derivatives[kCrbY](0, i) = 30.0 * std::cos(0.7 * i);
  }
  FisherInformation info;
  info.AddFrame(f);
  const double known_i0 = info.BoundVariance(kCrbD, {kCrbD});
  const double free_i0 = info.BoundVariance(kCrbD, {kCrbLnI0, kCrbD});
  const double free_all = info.BoundVariance(kCrbD, {kCrbLnI0, kCrbX, kCrbY, kCrbD});
  ASSERT_TRUE(std::isfinite(free_i0) && std::isfinite(free_all));
  EXPECT_GT(free_i0, known_i0);
  EXPECT_GE(free_all, free_i0 * (1.0 - 1e-12));
  const CrbResult r = ComputeFrameCrb({f}, false);
  EXPECT_TRUE(r.valid);
  EXPECT_NEAR(r.d_sd_mm, std::sqrt(free_all), 1e-9 * r.d_sd_mm);
  EXPECT_LT(r.theta_sd_deg, 0.0);  // theta held known
  EXPECT_NEAR(r.signal_e, 1e5, 1e-6);
}

}  // namespace
}  // namespace irdist
