#include "estimator/edge_phase.h"

#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "base/pi.h"

namespace irdist {
namespace {

// Sizes of discs R = 9.1 px x 1500 / d over 1.5..3 m, centres at random phases, with a smooth
// bias (a quadratic in 1000 / d), noise of `noise_sd` and an edge error e(p) = amplitude x
// cos(2 pi p + 0.7) at each of the four axis-parallel edge points (their mean, on the radius).
std::vector<EdgePhaseSample> Samples(double amplitude, double noise_sd, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> phase(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, noise_sd);
  std::vector<EdgePhaseSample> out;
  for (int i = 0; i < 64; ++i) {
    const double d_mm = 1500.0 + 1500.0 * i / 63.0;
    const double u = 1000.0 / d_mm;
    const double radius = 9.1 * 1500.0 / d_mm;
    EdgePhaseSample s;
    s.center_x_px = 20.0 + phase(rng);
    s.center_y_px = 20.0 + phase(rng);
    double edge = 0.0;
    for (const double p : {radius + s.center_x_px, radius - s.center_x_px,
                           radius + s.center_y_px, radius - s.center_y_px}) {
      edge += 0.25 * amplitude * std::cos(2.0 * kPi * p + 0.7);
    }
    const double fitted = radius * (1.0 + 1e-3 * (0.5 - 0.3 * u + 0.1 * u * u) + edge +
                                    noise(rng));
    s.size_var_px2 = fitted * fitted / 4.0;
    s.d_mm = d_mm;
    out.push_back(s);
  }
  return out;
}

TEST(EdgePhase, FindsTheSizesPartThatFollowsThePhase) {
  const EdgePhase none = EdgePhaseOf(Samples(0.0, 0.0, 1));
  ASSERT_TRUE(none.ok);
  EXPECT_LT(none.rms, 1e-9);  // the smooth bias is not phase
  const EdgePhase some = EdgePhaseOf(Samples(2e-3, 0.0, 1));
  // The mean of four cosines of amplitude a: rms a / 2 x rms(w) over uniform centres = a / 2.
  EXPECT_GT(some.rms, 0.6e-3);
  EXPECT_LT(some.rms, 1.4e-3);
  EXPECT_NEAR(some.peak_to_peak, 4e-3, 1.5e-3);
}

// With noise and no phase, rms reads the noise's share, and noise_rms says so.
TEST(EdgePhase, SaysWhatTheNoiseAloneReads) {
  double sum = 0.0, noise_sum = 0.0;
  for (unsigned seed = 1; seed <= 20; ++seed) {
    const EdgePhase e = EdgePhaseOf(Samples(0.0, 5e-4, seed));
    sum += e.rms / 20.0;
    noise_sum += e.noise_rms / 20.0;
  }
  EXPECT_NEAR(sum / noise_sum, 1.0, 0.25);
}

TEST(EdgePhase, NeedsEnoughSamples) {
  std::vector<EdgePhaseSample> few = Samples(0.0, 0.0, 1);
  few.resize(kMinEdgePhaseSamples - 1);
  EXPECT_FALSE(EdgePhaseOf(few).ok);
}

}  // namespace
}  // namespace irdist
