// The constant-velocity track (estimator/track_filter.h): consistent with its own standard errors
// on a target that moves as its model says, the velocity of a steady motion within 3 standard
// errors, an outlier frame gated without moving the track, a jump restarted after reset_after
// frames, bad input refused.
#include "estimator/track_filter.h"

#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "base/check.h"

namespace irdist {
namespace {

constexpr double kFrameS = 0.01;  // 100 frames per second

TEST(TrackFilter, NormalisedErrorsAreOneOnATargetThatMovesAsTheModelSays) {
  // White acceleration of the filter's own power spectral density: the truth is a draw of the
  // model, so the errors over the filter's standard errors have unit rms (NEES), per axis.
  TrackFilterOptions options;
  options.accel_psd_mm2_per_s3 = 2e4;
  double sum_p = 0.0, sum_v = 0.0;
  int n = 0;
  for (int seed = 1; seed <= 20; ++seed) {
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> normal(0.0, 1.0);
    TrackFilter filter(1, options);
    double p = 2000.0, v = 300.0;
    const double sd = 0.8;
    for (int k = 0; k < 400; ++k) {
      if (k > 0) {  // the exact discretisation of white acceleration over one frame
        const double q = options.accel_psd_mm2_per_s3, dt = kFrameS;
        const double w1 = normal(rng) * std::sqrt(q * dt);
        const double w2 = normal(rng) * std::sqrt(q * dt * dt * dt / 12.0);
        p += v * dt + 0.5 * dt * w1 + w2;
        v += w1;
      }
      const TrackState s = filter.Add(k * kFrameS, {p + sd * normal(rng)}, {sd});
      ASSERT_TRUE(s.used) << "seed " << seed << " frame " << k << " chi2 " << s.chi2;
      if (k < 50) continue;  // the start's prior forgotten
      sum_p += std::pow((s.position_mm[0] - p) / s.position_sd_mm[0], 2);
      sum_v += std::pow((s.velocity_mm_per_s[0] - v) / s.velocity_sd_mm_per_s[0], 2);
      ++n;
    }
  }
  EXPECT_NEAR(std::sqrt(sum_p / n), 1.0, 0.1);
  EXPECT_NEAR(std::sqrt(sum_v / n), 1.0, 0.1);
}

TEST(TrackFilter, ASteadyMotionsVelocityWithinThreeStandardErrorsAndThePositionSmoothed) {
  // The slide at 0.5 m/s from 1.5 m, 1 mm per frame of noise: the moving-slide case.
  std::mt19937_64 rng(3);
  std::normal_distribution<double> noise(0.0, 1.0);
  TrackFilter filter(1);
  double raw2 = 0.0, smooth2 = 0.0;
  TrackState last;
  for (int k = 0; k < 300; ++k) {
    const double t = k * kFrameS, truth = 1500.0 + 500.0 * t;
    last = filter.Add(t, {truth + noise(rng)}, {1.0});
    if (k < 50) continue;
    raw2 += 1.0;
    smooth2 += std::pow(last.position_mm[0] - truth, 2);
  }
  EXPECT_LT(std::abs(last.velocity_mm_per_s[0] - 500.0), 3.0 * last.velocity_sd_mm_per_s[0]);
  EXPECT_LT(last.velocity_sd_mm_per_s[0], 50.0);  // informative: 10% of the speed at most
  EXPECT_LT(smooth2, 0.8 * raw2);                  // the track is better than a frame
  EXPECT_EQ(last.frames, 300);
}

TEST(TrackFilter, AnOutlierFrameIsGatedAndLeavesTheTrackAsAMissingFrameWould) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<double> z;
  for (int k = 0; k < 60; ++k) z.push_back(2000.0 + 100.0 * k * kFrameS + noise(rng));
  TrackFilter with_outlier(1), with_gap(1);
  TrackState a, b;
  for (int k = 0; k < 60; ++k) {
    const double t = k * kFrameS;
    a = with_outlier.Add(t, {k == 40 ? z[k] + 60.0 : z[k]}, {1.0});
    b = with_gap.Add(t, {k == 40 ? NAN : z[k]}, {1.0});
    if (k == 40) {
      EXPECT_FALSE(a.used);
      EXPECT_FALSE(a.started);
      EXPECT_GT(a.chi2, 24.0);
      EXPECT_FALSE(b.used);
    }
  }
  EXPECT_DOUBLE_EQ(a.position_mm[0], b.position_mm[0]);
  EXPECT_DOUBLE_EQ(a.velocity_mm_per_s[0], b.velocity_mm_per_s[0]);
}

TEST(TrackFilter, AJumpRestartsTheTrackAfterResetAfterAgreeingFrames) {
  TrackFilterOptions options;
  options.reset_after = 3;
  TrackFilter filter(1, options);
  for (int k = 0; k < 50; ++k) filter.Add(k * kFrameS, {1800.0}, {0.5});
  // The target is now 200 mm further (another IRED, a knocked mount).
  TrackState s = filter.Add(50 * kFrameS, {2000.0}, {0.5});
  EXPECT_FALSE(s.used);
  s = filter.Add(51 * kFrameS, {2000.2}, {0.5});
  EXPECT_FALSE(s.used);
  EXPECT_NEAR(s.position_mm[0], 1800.0, 1.0);  // still the old track
  s = filter.Add(52 * kFrameS, {1999.9}, {0.5});
  EXPECT_TRUE(s.started);
  EXPECT_TRUE(s.used);
  EXPECT_DOUBLE_EQ(s.position_mm[0], 1999.9);
  EXPECT_EQ(s.frames, 1);
  s = filter.Add(53 * kFrameS, {2000.1}, {0.5});
  EXPECT_TRUE(s.used);
  EXPECT_NEAR(s.position_mm[0], 2000.0, 0.5);
}

TEST(TrackFilter, GatedFramesThatDisagreeWithEachOtherDoNotRestart) {
  TrackFilter filter(1);
  for (int k = 0; k < 50; ++k) filter.Add(k * kFrameS, {1800.0}, {0.5});
  const double wild[] = {2000.0, 1600.0, 2100.0, 1500.0, 2200.0};
  for (int i = 0; i < 5; ++i) {
    const TrackState s = filter.Add((50 + i) * kFrameS, {wild[i]}, {0.5});
    EXPECT_FALSE(s.used) << i;
    EXPECT_FALSE(s.started) << i;
  }
  EXPECT_TRUE(filter.Add(55 * kFrameS, {1800.2}, {0.5}).used);
}

TEST(TrackFilter, ThreeAxesGateTogether) {
  // A steady track (little process noise, so the prediction's variance is small beyond the
  // frame's): a frame 3 sd off on every axis (chi-square about 27) is within the 3-axis gate (30.7
  // at 1e-6), 4 sd off on every axis (about 48) beyond it, though each axis alone is within the
  // one-axis gate (23.9).
  TrackFilterOptions options;
  options.accel_psd_mm2_per_s3 = 1.0;
  const std::vector<double> sd = {0.3, 0.3, 1.0};
  TrackFilter within(3, options), beyond(3, options);
  for (int k = 0; k < 200; ++k) {
    const std::vector<double> z = {10.0 + k, -5.0, 2000.0 - 2.0 * k};
    within.Add(k * kFrameS, z, sd);
    beyond.Add(k * kFrameS, z, sd);
  }
  const TrackState in = within.Add(2.0, {210.0 + 0.9, -5.0 - 0.9, 1600.0 + 3.0}, sd);
  EXPECT_TRUE(in.used) << in.chi2;
  EXPECT_GT(in.chi2, 23.9);
  const TrackState out = beyond.Add(2.0, {210.0 + 1.2, -5.0 - 1.2, 1600.0 + 4.0}, sd);
  EXPECT_FALSE(out.used) << out.chi2;
  EXPECT_LT(out.chi2, 3.0 * 23.9);
  EXPECT_NEAR(in.velocity_mm_per_s[0], 100.0, 2.0);
  EXPECT_NEAR(in.velocity_mm_per_s[2], -200.0, 4.0);
}

TEST(TrackFilter, BadInputIsRefused) {
  TrackFilterOptions bad;
  bad.accel_psd_mm2_per_s3 = NAN;
  EXPECT_THROW(TrackFilter(1, bad), CheckError);
  bad = {};
  bad.gate_tail_probability = 0.0;
  EXPECT_THROW(TrackFilter(1, bad), CheckError);
  EXPECT_THROW(TrackFilter(4), CheckError);
  EXPECT_THROW(TrackFilter(0), CheckError);
  TrackFilter filter(1);
  filter.Add(1.0, {2000.0}, {1.0});
  EXPECT_THROW(filter.Add(1.0, {2000.0}, {1.0}), CheckError);  // time must advance
  EXPECT_THROW(filter.Add(0.5, {2000.0}, {1.0}), CheckError);
  EXPECT_THROW(filter.Add(2.0, {2000.0, 1.0}, {1.0}), CheckError);
  const TrackState s = filter.Add(2.0, {2000.0}, {-1.0});  // a negative sd: not a measurement
  EXPECT_FALSE(s.used);
}

}  // namespace
}  // namespace irdist
