// The tabulated normal (estimator/normal_table.h) against std::erfc and std::exp: the blob fit's
// model must not move when its edges are read from the table.
#include "estimator/normal_table.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

namespace irdist {
namespace {

double ExactCdf(double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); }
double ExactPdf(double x) { return std::exp(-0.5 * x * x) / std::sqrt(2.0 * M_PI); }

TEST(NormalTable, AgreesWithErfcAndExpEverywhereToAFewTenthsOfANano) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> uniform(-10.0, 10.0);
  double worst_cdf = 0.0, worst_pdf = 0.0;
  for (int i = 0; i < 200000; ++i) {
    const double x = uniform(rng);
    const NormalValues v = NormalAt(x);
    worst_cdf = std::max(worst_cdf, std::fabs(v.cdf - ExactCdf(x)));
    worst_pdf = std::max(worst_pdf, std::fabs(v.pdf - ExactPdf(x)));
  }
  EXPECT_LT(worst_cdf, 3e-10);
  EXPECT_LT(worst_pdf, 6e-10);
}

TEST(NormalTable, ExactAtNodesAndAtTheReach) {
  for (double x : {-9.0, -2.0, -1.0 / 64.0, 0.0, 0.5, 3.25, 8.984375}) {
    const NormalValues v = NormalAt(x);
    EXPECT_NEAR(v.cdf, ExactCdf(x), 1e-15) << x;
    EXPECT_NEAR(v.pdf, ExactPdf(x), 1e-15) << x;
  }
  EXPECT_EQ(NormalAt(-20.0).cdf, 0.0);
  EXPECT_EQ(NormalAt(20.0).cdf, 1.0);
  EXPECT_EQ(NormalAt(20.0).pdf, 0.0);
  EXPECT_EQ(NormalAt(-HUGE_VAL).cdf, 0.0);
  EXPECT_TRUE(std::isnan(NormalAt(NAN).cdf));
}

// The interpolant is smooth: Phi's difference quotient across a cell boundary is phi.
TEST(NormalTable, CdfSlopeIsThePdfAcrossCells) {
  for (double x = -6.0; x < 6.0; x += 0.37) {
    const double h = 1e-5;
    const double slope = (NormalAt(x + h).cdf - NormalAt(x - h).cdf) / (2 * h);
    EXPECT_NEAR(slope, ExactPdf(x), 1e-7) << x;
  }
}

}  // namespace
}  // namespace irdist
