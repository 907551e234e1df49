// The start polynomials' real roots (estimator/polynomial_roots.h).
#include "estimator/polynomial_roots.h"

#include <gtest/gtest.h>

#include <cmath>

namespace irdist {
namespace {

TEST(RealRoots, ACubicsThreeRootsAscending) {
  // (x - 0.5)(x - 2)(x - 3) = x^3 - 5.5 x^2 + 8.5 x - 3
  const double poly[4] = {-3.0, 8.5, -5.5, 1.0};
  double roots[3];
  ASSERT_EQ(RealRoots(poly, roots), 3);
  EXPECT_NEAR(roots[0], 0.5, 1e-12);
  EXPECT_NEAR(roots[1], 2.0, 1e-12);
  EXPECT_NEAR(roots[2], 3.0, 1e-12);
}

TEST(RealRoots, ComplexPairsAreLeftOutAndDoubleRootsKept) {
  // (x - 1)(x^2 + 1): one real root.
  const double one[4] = {-1.0, 1.0, -1.0, 1.0};
  double roots[3];
  ASSERT_EQ(RealRoots(one, roots), 1);
  EXPECT_NEAR(roots[0], 1.0, 1e-12);
  // (x - 2)^2 (x + 1) = x^3 - 3 x^2 + 4: the double root comes out of the eigen solver as a pair
  // with a tiny imaginary part, and counts.
  const double twice[4] = {4.0, 0.0, -3.0, 1.0};
  const int n = RealRoots(twice, roots);
  ASSERT_EQ(n, 3);
  EXPECT_NEAR(roots[0], -1.0, 1e-9);
  EXPECT_NEAR(roots[1], 2.0, 1e-6);
  EXPECT_NEAR(roots[2], 2.0, 1e-6);
}

TEST(RealRoots, ATinyLeadingCoefficientIsALowerDegree) {
  const double quadratic[4] = {-4.0, 0.0, 1.0, 1e-15};  // x^2 - 4
  double roots[3];
  ASSERT_EQ(RealRoots(quadratic, roots), 2);
  EXPECT_NEAR(roots[0], -2.0, 1e-12);
  EXPECT_NEAR(roots[1], 2.0, 1e-12);
  const double linear[4] = {3.0, -1.5, 0.0, 0.0};
  ASSERT_EQ(RealRoots(linear, roots), 1);
  EXPECT_NEAR(roots[0], 2.0, 1e-15);
  const double zero[4] = {0.0, 0.0, 0.0, 0.0};
  EXPECT_EQ(RealRoots(zero, roots), 0);
}

TEST(NormaliseToUnitNorm, ScalesToUnitNormAndLeavesZero) {
  double poly[4] = {3.0, 0.0, 4.0, 0.0};
  NormaliseToUnitNorm(poly);
  EXPECT_DOUBLE_EQ(poly[0], 0.6);
  EXPECT_DOUBLE_EQ(poly[2], 0.8);
  double zero[4] = {0.0, 0.0, 0.0, 0.0};
  NormaliseToUnitNorm(zero);
  EXPECT_EQ(zero[0], 0.0);
}

}  // namespace
}  // namespace irdist
