// The blob fit's standard errors from its covariance (estimator/blob_fit_errors.h), against their
// closed forms. (Their agreement with the frames' scatter: blob_fit_test.cc,
// TheSizesErrorsAreTheirScatter.)
#include "estimator/blob_fit_errors.h"

#include <gtest/gtest.h>

#include <cmath>

namespace irdist {
namespace {

// A disc of semi-axes a (along x) and b: P = diag(1 / a^2, 1 / b^2), centre and the rest 0.
void Disc(double a, double b, double* v) {
  for (int i = 0; i < 7; ++i) v[i] = 0.0;
  v[2] = 1.0 / (a * a);
  v[4] = 1.0 / (b * b);
}

// P11 and P22 independent with variance s2 each, P12 with s12.
BlobCovariance Independent(double s2, double s12) {
  BlobCovariance c = BlobCovariance::Identity() * 1e-3;
  c(2, 2) = c(4, 4) = s2;
  c(3, 3) = s12;
  return c;
}

TEST(BlobFitErrors, TheTraceSizeIsTheHarmonicMeanOfTheAxesWithItsError) {
  double v[7];
  Disc(5.5, 4.6, v);
  const BlobCovariance c = Independent(1e-8, 4e-9);
  double var = 0.0, se = 0.0;
  TraceSize(c, v, 0.9, &var, &se);
  const double p = 0.5 * (v[2] + v[4]);
  EXPECT_NEAR(var, 0.25 / p, 1e-12);
  EXPECT_NEAR(var, 5.5 * 5.5 * 4.6 * 4.6 / (2.0 * (5.5 * 5.5 + 4.6 * 4.6)), 1e-12);
  EXPECT_NEAR(se, std::sqrt(0.5e-8) / (4.0 * p * p), 1e-12);  // var p = (s2 + s2) / 4
  double se_misfit = 0.0;
  TraceSize(c, v, 4.0, &var, &se_misfit);  // chi2 per pixel 4: twice the error
  EXPECT_NEAR(se_misfit, 2.0 * se, 1e-12);
  EXPECT_NEAR(AnisotropyNoiseVar(c), 0.25 * (1e-8 + 1e-8) + 4e-9, 1e-18);
}

// Clearly elliptical (the rule leaves |a| as it is when its noise is 0): the major axis's p is P11
// alone. Round within its noise (the rule takes |a| to 0): the trace size's error.
TEST(BlobFitErrors, TheMajorAxisErrorFollowsTheRoundBlobRule) {
  double v[7];
  Disc(5.5, 4.6, v);
  const BlobCovariance c = Independent(1e-8, 4e-9);
  EXPECT_NEAR(MajorVarSe(c, v, 0.0, v[2], 1.0), std::sqrt(1e-8) / (4.0 * v[2] * v[2]), 1e-12);
  Disc(5.0, 4.999, v);
  const double p = 0.5 * (v[2] + v[4]);
  double var = 0.0, trace_se = 0.0;
  TraceSize(c, v, 1.0, &var, &trace_se);
  EXPECT_NEAR(MajorVarSe(c, v, 1.0, p, 1.0), trace_se, 1e-9 * trace_se);
  EXPECT_TRUE(std::isnan(MajorVarSe(c, v, 0.0, 0.0, 1.0)));  // no disc
}

}  // namespace
}  // namespace irdist
