#include "estimator/crosstalk_kernel.h"

#include <gtest/gtest.h>

#include <vector>

namespace irdist {
namespace {

// The kernel's sum and its variance on the grid.
void Moments(const std::vector<double>& k, double* sum, double* var) {
  const int reach = static_cast<int>(k.size() / 2);
  *sum = 0.0;
  *var = 0.0;
  for (int n = -reach; n <= reach; ++n) {
    *sum += k[n + reach];
    *var += k[n + reach] * n * n;
  }
}

TEST(CrosstalkKernel, NoCrosstalkIsTheIdentity) {
  EXPECT_EQ(CrosstalkKernel(0.0, 0.0), std::vector<double>{1.0});
  EXPECT_EQ(CrosstalkKernel(0.0, 1.0), std::vector<double>{1.0});
}

// A small crosstalk (a Table 3 calibration of the virtual rig: 0.0015 px^2) reaches one pixel:
// its next taps (1e-9) move no gray level, and each tap kept costs the blob fit time.
TEST(CrosstalkKernel, ASmallCrosstalkReachesOnePixel) {
  const std::vector<double> k = CrosstalkKernel(0.0015, 0.002);
  ASSERT_EQ(k.size(), 3u);
  EXPECT_NEAR(k[0], 0.0015 / 2.0, 1e-5);
}

// Whatever the mix of the two shapes, the kernel carries the asked variance (the sampled
// Gaussian's sd is found for it, not taken as sqrt(var)), sums to 1, is odd and symmetric.
TEST(CrosstalkKernel, CarriesTheAskedVarianceForEveryShare) {
  for (double var : {0.005, 0.05, 0.3, 1.0}) {
    for (double share : {0.0, 0.3, 1.0}) {
      SCOPED_TRACE(testing::Message() << "var " << var << " share " << share);
      const std::vector<double> k = CrosstalkKernel(var, share);
      ASSERT_EQ(k.size() % 2, 1u);
      double sum = 0.0, got = 0.0;
      Moments(k, &sum, &got);
      EXPECT_NEAR(sum, 1.0, 1e-12);  // normalised after the taps below 1e-7 were dropped
      EXPECT_NEAR(got, var, 1e-6 + 1e-5 * var);  // the dropped tail: 5e-6 of 1 px^2
      for (size_t i = 0; i < k.size() / 2; ++i) EXPECT_DOUBLE_EQ(k[i], k[k.size() - 1 - i]);
    }
  }
}

// A lattice walk is not a sampled Gaussian of the same variance: its centre tap is larger (charge
// that never hopped), and the cached kernel is the new one after the arguments change.
TEST(CrosstalkKernel, TheLatticeWalkDiffersFromTheGaussianAndTheCacheFollows) {
  const std::vector<double> gaussian = CrosstalkKernel(0.5, 0.0);
  const std::vector<double> walk = CrosstalkKernel(0.5, 1.0);
  EXPECT_GT(walk[walk.size() / 2], gaussian[gaussian.size() / 2] + 0.01);
  EXPECT_EQ(CrosstalkKernel(0.5, 0.0), gaussian);
}

}  // namespace
}  // namespace irdist
