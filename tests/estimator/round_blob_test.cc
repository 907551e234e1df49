#include "estimator/round_blob.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "base/pi.h"
#include "estimator/psf_anisotropy.h"

namespace irdist {
namespace {

// A disc of 6 px radius (variance 9 px^2 along its axes face-on), 1 px^2 of blur, its major axis
// along x. One 33 ms frame's anisotropy noise is set so that a 5 deg tilt gives t = 7.5 (|a|^2 of
// 6.5x the noise), as the virtual rig's 5 deg pose at 2 m; a frame of `share` of that signal has
// 1 / share of that noise.
constexpr double kDiscVarPx2 = 9.0, kBlurPx2 = 1.0;
double HalfTrace(double theta_deg) {
  const double c2 = std::pow(std::cos(theta_deg * kPi / 180.0), 2);
  return 0.5 * (0.25 / kDiscVarPx2 + 0.25 / (kDiscVarPx2 * c2));
}
double TrueRoot(double theta_deg) {
  const double c2 = std::pow(std::cos(theta_deg * kPi / 180.0), 2);
  return 0.5 * (0.25 / (kDiscVarPx2 * c2) - 0.25 / kDiscVarPx2);
}
const double kFrameNoise = TrueRoot(5.0) * TrueRoot(5.0) / 6.5;

// One frame as the blob fit leaves it (blob_fit.cc RefineWithBlobFit): the fitted anisotropy
// (the true one plus noise of E|a_noise|^2 = noise), its raw axes, and the axes after one frame's
// round-blob rule, with the blur added.
Features FittedFrame(double theta_deg, double share, std::mt19937_64* rng) {
  const double noise = kFrameNoise / share;
  std::normal_distribution<double> part(0.0, std::sqrt(noise / 2.0));
  const double c = -TrueRoot(theta_deg) + part(*rng), s = part(*rng);
  const double length = std::hypot(c, s), half_trace = HalfTrace(theta_deg);
  Features f;
  f.ellipse_moments.valid = true;
  f.ellipse_moments.angle_deg = 0.5 * std::atan2(-s, -c) * 180.0 / kPi;
  f.disc_raw_angle_deg = f.ellipse_moments.angle_deg;
  f.disc_raw_major_var_px2 = 0.25 / (half_trace - length);
  f.disc_raw_minor_var_px2 = 0.25 / (half_trace + length);
  f.disc_aniso_noise_var = noise;
  const double root = std::sqrt(DenoisedAnisotropy2(length * length, noise));
  f.size_blur_var_px2 = kBlurPx2;
  f.moment_major_var_px2 = 0.25 / (half_trace - root) + kBlurPx2;
  f.moment_minor_var_px2 = 0.25 / (half_trace + root) + kBlurPx2;
  return f;
}

double ThetaDeg(const Features& f) {
  const double ratio = (f.moment_minor_var_px2 - kBlurPx2) / (f.moment_major_var_px2 - kBlurPx2);
  return std::acos(std::sqrt(ratio)) * 180.0 / kPi;
}

// A bracket of 8 ms + 30, 33, 36 ms (the signal's shares against one 33 ms frame), pooled;
// returns its 33 ms frame's theta, and one frame's own in `alone`.
double BracketTheta(double theta_deg, std::mt19937_64* rng, double* alone) {
  std::vector<Features> frames;
  for (double t_ms : {8.0, 30.0, 33.0, 36.0})
    frames.push_back(FittedFrame(theta_deg, t_ms / 33.0, rng));
  *alone = ThetaDeg(frames[2]);
  std::vector<Features*> pointers;
  for (Features& f : frames) pointers.push_back(&f);
  PoolRoundBlobRule(pointers);
  return ThetaDeg(frames[2]);
}

TEST(RoundBlobRule, ABracketsFramesTogetherReadARoundBlobAsRoundWhereOneFrameFails) {
  std::mt19937_64 rng(5);
  int pooled_far = 0, alone_far = 0;
  const int brackets = 4000;
  for (int i = 0; i < brackets; ++i) {
    double alone;
    pooled_far += BracketTheta(0.0, &rng, &alone) > 2.0;
    alone_far += alone > 2.0;
  }
  std::printf("round blobs beyond 2 deg: %d of %d with one frame's rule, %d pooled\n", alone_far,
              brackets, pooled_far);
  // One frame's rule: about 1% of round blobs read beyond 2 deg; the pooled rule: about 0.1%.
  EXPECT_GT(alone_far, 0.006 * brackets);
  EXPECT_LT(pooled_far, 0.003 * brackets);
}

// The pool takes each frame's anisotropy from the fit's own axes, not the moment ellipse's angle,
// which the line of sight turns (a round blob's then the turn's own direction): a bracket whose
// ellipse angles were turned pools as it did before the turn.
TEST(RoundBlobRule, ThePoolDoesNotReadTheTurnedEllipsesAngle) {
  std::mt19937_64 rng(8);
  for (int i = 0; i < 200; ++i) {
    std::vector<Features> frames, turned;
    for (double share : {0.25, 1.0, 1.1}) frames.push_back(FittedFrame(0.0, share, &rng));
    turned = frames;
    for (Features& f : turned) f.ellipse_moments.angle_deg = 52.5;
    PoolRoundBlobRule({&frames[0], &frames[1], &frames[2]});
    PoolRoundBlobRule({&turned[0], &turned[1], &turned[2]});
    for (int k = 0; k < 3; ++k) {
      ASSERT_EQ(turned[k].moment_major_var_px2, frames[k].moment_major_var_px2) << i;
      ASSERT_EQ(turned[k].moment_minor_var_px2, frames[k].moment_minor_var_px2) << i;
    }
  }
}

TEST(RoundBlobRule, SmallAndLargeTiltsKeepTheirThetaInABracket) {
  std::mt19937_64 rng(6);
  for (double theta_deg : {5.0, 10.0, 20.0}) {
    double sum = 0.0, alone;
    const int brackets = 2000;
    for (int i = 0; i < brackets; ++i) sum += BracketTheta(theta_deg, &rng, &alone) / brackets;
    std::printf("%.0f deg: pooled mean %.3f deg\n", theta_deg, sum);
    // 5 deg: the pooled t ~ 22 keeps it whole (the mean's bias, from |a|^(1/2), within 0.15 deg).
    EXPECT_NEAR(sum, theta_deg, theta_deg < 6.0 ? 0.15 : 0.05) << theta_deg;
  }
}

TEST(RoundBlobRule, FramesWithoutTheFitsAnisotropyAndChangesSinceTheFitAreKept) {
  std::mt19937_64 rng(7);
  Features a = FittedFrame(20.0, 1.0, &rng), b = FittedFrame(20.0, 1.0, &rng);
  Features moments = a;  // the moments' path: no anisotropy noise
  moments.disc_aniso_noise_var = std::nan("");
  const Features moments_before = moments;
  // A change since the fit (a refocused blur, the line of sight): b's axes 0.2 px^2 apart more.
  b.moment_major_var_px2 += 0.1;
  b.moment_minor_var_px2 -= 0.1;
  const double b_trace =
      0.25 / (b.moment_major_var_px2 - kBlurPx2) + 0.25 / (b.moment_minor_var_px2 - kBlurPx2);
  Features a_alone = a;
  PoolRoundBlobRule({&a_alone});  // one frame: nothing to pool
  EXPECT_EQ(a_alone.moment_major_var_px2, a.moment_major_var_px2);
  const Features a_before = a, b_before = b;
  PoolRoundBlobRule({&a, &b, &moments});
  EXPECT_EQ(moments.moment_major_var_px2, moments_before.moment_major_var_px2);
  EXPECT_NEAR(
      0.25 / (b.moment_major_var_px2 - kBlurPx2) + 0.25 / (b.moment_minor_var_px2 - kBlurPx2),
      b_trace, 1e-12);
  // Both frames now carry the pool's |a|, b keeping what moved its axes since its own rule.
  auto root = [](const Features& f) {
    return 0.5 * (0.25 / (f.moment_minor_var_px2 - kBlurPx2) -
                  0.25 / (f.moment_major_var_px2 - kBlurPx2));
  };
  auto rule_root = [](const Features& f) {
    const double length = 0.5 * (0.25 / f.disc_raw_minor_var_px2 - 0.25 / f.disc_raw_major_var_px2);
    return std::sqrt(DenoisedAnisotropy2(length * length, f.disc_aniso_noise_var));
  };
  EXPECT_NEAR(root(a_before), rule_root(a), 1e-12);
  EXPECT_NEAR(root(b) - root(a), root(b_before) - rule_root(b), 1e-12);
  EXPECT_GT(root(a), std::min(rule_root(a), rule_root(b)) - 0.2 * std::sqrt(kFrameNoise));
  EXPECT_LT(root(a), std::max(rule_root(a), rule_root(b)));
}

}  // namespace
}  // namespace irdist
