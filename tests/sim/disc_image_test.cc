#include "sim/disc_image.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include <opencv2/core.hpp>

// The exact image of a bright disc (sim/disc_image.h, sim-internal, the Scene's geometry):
// figures from a pinhole camera's geometry (a disc of radius R facing the camera at distance D
// images as a circle of radius f R / D centred at f X / D), Gauss-Legendre quadrature's textbook
// nodes and exactness, and the pixel response's normalisation.

namespace irdist::sim::disc_image {
namespace {

constexpr double kF = 25.0;  // focal length, mm

TEST(GaussLegendre, NodesAndWeightsAreTheTextbookOnesAndExactToDegreeTwoNMinusOne) {
  std::vector<double> x, w;
  GaussLegendre(2, &x, &w);
  EXPECT_NEAR(x[0], -1.0 / std::sqrt(3.0), 1e-14);
  EXPECT_NEAR(x[1], 1.0 / std::sqrt(3.0), 1e-14);
  EXPECT_NEAR(w[0], 1.0, 1e-14);
  GaussLegendre(3, &x, &w);
  EXPECT_NEAR(x[0], -std::sqrt(0.6), 1e-14);
  EXPECT_NEAR(x[1], 0.0, 1e-14);
  EXPECT_NEAR(w[0], 5.0 / 9.0, 1e-14);
  EXPECT_NEAR(w[1], 8.0 / 9.0, 1e-14);
  for (int n : {4, 7, 12}) {
    GaussLegendre(n, &x, &w);
    for (int k = 0; k <= 2 * n - 1; ++k) {  // integral of x^k over [-1, 1]
      double sum = 0.0;
      for (int i = 0; i < n; ++i) sum += w[i] * std::pow(x[i], k);
      EXPECT_NEAR(sum, k % 2 == 0 ? 2.0 / (k + 1) : 0.0, 1e-13) << "n " << n << " k " << k;
    }
  }
}

// Without blur a pixel sees exactly its own square; with blur the responses of all pixels still
// add up to 1 everywhere (no light is lost or made), and H is h's running integral.
TEST(PixelResponse, IsTheUnitBoxWithoutBlurAndAPartitionOfUnityWithIt) {
  const PixelResponse sharp(0.0);
  EXPECT_EQ(sharp.h(0.0), 1.0);
  EXPECT_EQ(sharp.h(0.49), 1.0);
  EXPECT_EQ(sharp.h(0.51), 0.0);
  EXPECT_NEAR(sharp.H(0.0), 0.5, 1e-12);
  EXPECT_NEAR(sharp.H(0.25), 0.75, 1e-12);
  EXPECT_EQ(sharp.H(-0.6), 0.0);
  EXPECT_EQ(sharp.H(0.6), 1.0);
  const PixelResponse blurred(1.3);
  for (double x : {0.0, 0.17, 0.5, 0.93}) {
    double sum = 0.0;
    for (int k = -20; k <= 20; ++k) sum += blurred.h(x + k);
    EXPECT_NEAR(sum, 1.0, 1e-9) << x;
  }
  EXPECT_NEAR(blurred.H(0.0), 0.5, 1e-12);
  const double dx = 1e-5;  // H' = h
  EXPECT_NEAR((blurred.H(0.7 + dx) - blurred.H(0.7 - dx)) / (2 * dx), blurred.h(0.7), 1e-7);
}

// A disc of radius 50 mm facing the camera at 2000 mm, 100 mm right of its axis: a circle of
// radius 25 * 50 / 2000 = 0.625 mm centred at u = 25 * 100 / 2000 = 1.25 mm.
TEST(DiscConic, AFacingDiscImagesAsTheCircleOfPinholeGeometry) {
  const DiscConic k = MakeDiscConic({0, 0, 1}, {100, 0, 2000}, 50.0 * 50.0, kF);
  ASSERT_TRUE(k.in_view);
  EXPECT_NEAR(k.v_mid, 0.0, 1e-12);
  EXPECT_NEAR(k.v_half, 0.625, 1e-12);
  double left = 0.0, right = 0.0;
  k.Chord(0.0, &left, &right);
  EXPECT_NEAR(left, 1.25 - 0.625, 1e-12);
  EXPECT_NEAR(right, 1.25 + 0.625, 1e-12);
  k.Chord(0.5, &left, &right);  // half-chord sqrt(r^2 - v^2) = 0.375
  EXPECT_NEAR(right - left, 2 * 0.375, 1e-12);
  EXPECT_LT(k.Value(1.25, 0.0), 0.0);
  EXPECT_GT(k.Value(1.25 + 0.64, 0.0), 0.0);
  EXPECT_GT(k.Value(1.25, 0.63), 0.0);
}

// A disc seen edge-on (its normal across the line of sight) has no area in the image.
TEST(DiscConic, ADiscSeenEdgeOnIsNotInView) {
  EXPECT_FALSE(MakeDiscConic({1, 0, 0}, {0, 0, 2000}, 2500.0, kF).in_view);
}

// An edge through the facing disc's centre along its vertical, covering the side x > centre:
// every chord ends at the centre's image, u = 1.25 mm.
TEST(ImageCut, AnEdgeThroughTheCentreLeavesTheLeftHalfVisible) {
  const Vec3 n{0, 0, 1}, c{100, 0, 2000};
  const DiscConic k = MakeDiscConic(n, c, 2500.0, kF);
  const ImageCut cut = MakeImageCut(n, c, {1, 0, 0}, 0.0, kF);
  for (double v : {-0.5, 0.0, 0.3}) {
    double left = 0.0, right = 0.0;
    k.Chord(v, &left, &right);
    const double full_left = left;
    cut.Clip(v, &left, &right);
    EXPECT_NEAR(left, full_left, 1e-12);
    EXPECT_NEAR(right, 1.25, 1e-12) << v;
  }
  // Moved 30 mm along w, the edge's image moves 25 * 30 / 2000 = 0.375 mm.
  const ImageCut moved = MakeImageCut(n, c, {1, 0, 0}, 30.0, kF);
  double left = 0.0, right = 0.0;
  k.Chord(0.0, &left, &right);
  moved.Clip(0.0, &left, &right);
  EXPECT_NEAR(right, 1.25 + 0.375, 1e-12);
}

// An edge along the rows through the centre, covering y > centre: one visible range, the lower
// half of the circle in v (v from -0.625 to 0 mm).
TEST(VisibleRanges, AHorizontalEdgeThroughTheCentreLeavesOneHalf) {
  const Vec3 n{0, 0, 1}, c{0, 0, 2000};
  const DiscConic k = MakeDiscConic(n, c, 2500.0, kF);
  const std::vector<StripRange> ranges = VisibleRanges(k, MakeImageCut(n, c, {0, 1, 0}, 0.0, kF));
  ASSERT_EQ(ranges.size(), 1u);
  EXPECT_NEAR(ranges[0].v_mid, -0.3125, 1e-9);
  EXPECT_NEAR(ranges[0].v_half, 0.3125, 1e-9);
  // An edge beyond the disc covers nothing: the whole circle, in one or more ranges.
  const std::vector<StripRange> all = VisibleRanges(k, MakeImageCut(n, c, {0, 1, 0}, 80.0, kF));
  double covered = 0.0;
  for (const StripRange& r : all) covered += 2 * r.v_half;
  EXPECT_NEAR(covered, 2 * 0.625, 1e-9);
}

// One strip 4 px long on row 10 without blur: radiance x weight x scale on the 4 pixels it
// crosses, nothing elsewhere, added to what the image held.
TEST(IntegrateStrips, ASharpStripLightsExactlyThePixelsItCrosses) {
  const std::vector<ImageStrip> strips = {{10.5, 1.0, 3.0, 7.0, 2.0}};
  cv::Mat1f out(20, 12, 1.0f);
  IntegrateStrips(strips, PixelResponse(0.0), PixelResponse(0.0), 0.5, cv::Rect(0, 0, 12, 20),
                  &out);
  for (int r = 0; r < 20; ++r) {
    for (int c = 0; c < 12; ++c) {
      const float lit = (r == 10 && c >= 3 && c <= 6) ? 1.0f : 0.0f;
      EXPECT_NEAR(out(r, c), 1.0f + lit, 1e-6) << r << "," << c;
    }
  }
  // Blurred, the same light spreads but its total stays 2 x 4 x 0.5 = 4.
  cv::Mat1f blurred(40, 30, 0.0f);
  IntegrateStrips({{20.5, 1.0, 13.0, 17.0, 2.0}}, PixelResponse(1.5), PixelResponse(1.5), 0.5,
                  cv::Rect(-5, 0, 30, 40), &blurred);
  EXPECT_NEAR(cv::sum(blurred)[0], 4.0, 1e-4);
  EXPECT_GT(blurred(20, 20), blurred(20, 24));  // column 15 of the sensor = 20 of the rect
}

}  // namespace
}  // namespace irdist::sim::disc_image
