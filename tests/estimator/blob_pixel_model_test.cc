// The blob fit's pixel model (estimator/blob_pixel_model.h): its derivatives against finite
// differences, the response's split of the blur, the crosstalk's spreading on the pixel grid and
// a straight edge's pixel means against their closed form.
#include "estimator/blob_pixel_model.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <utility>
#include <vector>

#include "base/pi.h"
#include "estimator/blur_model.h"
#include "tests/estimator/pixel_responses.h"
#include "tests/estimator/ringing_table.h"

namespace irdist {
namespace blob_model {
namespace {

// The fit's analytic derivatives are those of its model: against central differences at points
// across the blurred edge of an ellipse (where the model varies), within the terms they leave out
// (the normal's turn across the pixel, the curvature's widening: 3% of the largest; `share`), and
// zero where the pixel is flat.
// The same with an elliptical PSF (psf_anisotropy.h): the edge's blur n^T S n for its normal.
void ExpectDerivativesAreFiniteDifferences(double aniso_c, double aniso_s, double optics_sd = 0.6,
                                           double optics_excess = 0.0, double share = 0.03) {
  PixelResponse response;
  response.optics_sd = optics_sd;
  response.gc_k = optics_excess / 24.0;
  response.aniso_c = aniso_c;
  response.aniso_s = aniso_s;
  const double v[5] = {10.3, 9.7, 1.0 / 36.0, 0.004, 1.0 / 25.0};  // semi-axes about 6 and 5 px
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> angle(0.0, 2.0 * kPi), radius(3.0, 9.0);
  int in_band = 0;
  for (int n = 0; n < 600; ++n) {
    const double a = angle(rng), r = radius(rng);
    const double x = v[0] + r * std::cos(a), y = v[1] + r * std::sin(a);
    double d[5];
    const double value = SquareMean(v, x, y, response, d);
    // Flat (to rounding); behind sharp optics the edge's far tails, 1e-3 of the step, where the
    // terms left out are a larger share of a vanishing slope.
    const double flat = optics_sd < 0.3 ? 1e-3 : 1e-6;
    if (value <= flat || value >= 1.0 - flat) continue;
    ++in_band;
    double numeric[5], largest = 0.0;
    for (int k = 0; k < 5; ++k) {
      const double h = 1e-6 * std::max(1.0, std::abs(v[k]));
      double up[5], down[5], ignored[5];
      std::copy(v, v + 5, up);
      std::copy(v, v + 5, down);
      up[k] += h;
      down[k] -= h;
      numeric[k] = (SquareMean(up, x, y, response, ignored) -
                    SquareMean(down, x, y, response, ignored)) / (2.0 * h);
      largest = std::max(largest, std::abs(numeric[k]) * (k < 2 ? 1.0 : 36.0));  // per P's scale
    }
    for (int k = 0; k < 5; ++k) {
      const double scale = k < 2 ? 1.0 : 1.0 / 36.0;
      EXPECT_NEAR(d[k], numeric[k], share * largest * scale + 1e-9)
          << "parameter " << k << " at (" << x << ", " << y << "), value " << value;
    }
  }
  EXPECT_GT(in_band, 100);
  double d[5] = {1, 1, 1, 1, 1};
  EXPECT_EQ(SquareMean(v, v[0] + 0.5, v[1], response, d), 1.0);  // well inside
  EXPECT_EQ(d[0], 0.0);
  EXPECT_EQ(SquareMean(v, v[0] + 20.0, v[1], response, d), 0.0);  // far outside
  EXPECT_EQ(d[2], 0.0);
}

TEST(BlobPixelModel, TheModelsDerivativesAreItsFiniteDifferences) {
  ExpectDerivativesAreFiniteDifferences(0.0, 0.0);
  ExpectDerivativesAreFiniteDifferences(0.03, -0.06);  // astigmatic: sd 0.68, 0.51 px, +-35 deg
  // Behind sharp optics the square is its four half-squares (0.15 px), or a blend of the two
  // (0.22 px).
  ExpectDerivativesAreFiniteDifferences(0.0, 0.0, 0.15);
  ExpectDerivativesAreFiniteDifferences(0.0, 0.0, 0.22);
  // An optics' edge beyond a Gaussian's (the Gram-Charlier term): a flat top and a peaked core,
  // whose curved edge widens by (2 + 4) sd^4 where a Gaussian's does by 2 sd^4 (blob_pixel_model.cc
  // TangentialExcess): the widening's change left out is 3x as large there (just under 4% of the
  // largest).
  ExpectDerivativesAreFiniteDifferences(0.0, 0.0, 0.6, -2.0);
  ExpectDerivativesAreFiniteDifferences(0.0, 0.0, 0.6, 4.0, 0.04);
}

// The edge correction is added to the pixel's mean at its offset from the edge (EdgeOffsetPx),
// linear between the table's knots, with its derivatives (the table's slope times the offset's,
// against central differences), and is 0 beyond the table, where the model is the edge's alone;
// a pixel the disc's edge sweeps past the table's end sees no step.
TEST(BlobPixelModel, TheEdgeCorrectionIsAddedAtTheEdgesOffsetAndEndsWithoutAStep) {
  PixelResponse plain;
  plain.optics_sd = 0.7;
  plain.gc_k = 4.0 / 24.0;
  PixelResponse corrected = plain;
  corrected.edge_correction = testing::RingingEdgeCorrection(0.02);
  const std::vector<double>& table = *corrected.edge_correction;
  const double v[5] = {10.3, 9.7, 1.0 / 49.0, 0.003, 1.0 / 42.0};
  double d[5], d_plain[5], ignored[5];
  for (const double x : {10.3, 12.05, 14.0, 16.62, 17.3, 19.0, 21.5}) {
    const double t = EdgeOffsetPx(v, x, 9.9, plain);
    const double k = (t + kEdgeCorrectionHalfWidthPx) / kEdgeCorrectionStepPx;
    double expected = 0.0;
    if (k >= 0.0 && k < kEdgeCorrectionKnots - 1) {
      const auto i = static_cast<size_t>(k);
      expected = table[i] + (k - static_cast<double>(i)) * (table[i + 1] - table[i]);
    }
    const double added =
        SquareMean(v, x, 9.9, corrected, d) - SquareMean(v, x, 9.9, plain, d_plain);
    EXPECT_NEAR(added, expected, 1e-12) << "x " << x << ", offset " << t;
    for (int p = 0; p < 5; ++p) {
      const double h = 1e-7 * std::max(1.0, std::abs(v[p]));
      double up[5], down[5];
      std::copy(v, v + 5, up);
      std::copy(v, v + 5, down);
      up[p] += h;
      down[p] -= h;
      const double numeric =
          (SquareMean(up, x, 9.9, corrected, ignored) - SquareMean(up, x, 9.9, plain, ignored) -
           SquareMean(down, x, 9.9, corrected, ignored) +
           SquareMean(down, x, 9.9, plain, ignored)) /
          (2.0 * h);
      EXPECT_NEAR(d[p] - d_plain[p], numeric, 1e-5 * (p < 2 ? 1.0 : 49.0))
          << "parameter " << p << " at x " << x;
    }
  }
  // The pixel at 12 px from the centre as the disc's radius passes 12 - 5 = 7 px (its offset
  // through the table's outer end): what the correction adds moves no faster than the table's
  // steepest slope allows.
  double steepest = 0.0;
  for (size_t i = 0; i + 1 < table.size(); ++i) {
    steepest = std::max(steepest, std::abs(table[i + 1] - table[i]) / kEdgeCorrectionStepPx);
  }
  double last = std::nan("");
  for (double r = 6.95; r <= 7.05; r += 0.001) {
    const double w[5] = {0.0, 0.0, 1.0 / (r * r), 0.0, 1.0 / (r * r)};
    const double added =
        SquareMean(w, 12.0, 0.0, corrected, d) - SquareMean(w, 12.0, 0.0, plain, d);
    if (std::isfinite(last)) {
      EXPECT_LE(std::abs(added - last), 1.01e-3 * steepest) << "R " << r;
    }
    last = added;
  }
  EXPECT_NE(last, 0.0);  // the pixel is inside the table at R = 7.05 px
}

// A pixel inside a small, blurred disc is the edge's, however near the centre it lies: as the
// disc's radius passes 1 / 0.3 of its distance from the centre, its value moves with the radius
// and nothing else (it was set to 1 within 0.3 R of the centre, a step of the edge's tail there:
// 0.006 of the amplitude behind a heavy-tailed edge of sd 1.1 px at R = 5.27 px, which moved the
// fitted size of an Airy PSF's disc by 0.04%). At the very centre, where the edge's normal is
// undefined, the value is its neighbours' and the derivatives finite.
TEST(BlobPixelModel, APixelNearTheCentreIsTheEdgesWhateverTheRadius) {
  for (const double excess : {0.0, 4.0, -2.0}) {
    PixelResponse response;
    response.optics_sd = 1.1;
    response.gc_k = excess / 24.0;
    const double x = 1.5, y = 0.5;                   // the pixel, from the disc's centre
    const double crossing = std::hypot(x, y) / 0.3;  // R = 5.27 px
    double d[5], last = std::nan("");
    for (double r = crossing - 0.01; r <= crossing + 0.01; r += 0.0005) {
      const double v[5] = {0.0, 0.0, 1.0 / (r * r), 0.0, 1.0 / (r * r)};
      const double value = SquareMean(v, x, y, response, d);
      if (std::isfinite(last)) {
        EXPECT_LT(std::abs(value - last), 2e-5) << "excess " << excess << ", R " << r;
      }
      last = value;
    }
    // The edge's tail reaches the pixel: it is not the disc's full brightness.
    EXPECT_GT(std::abs(1.0 - last), excess == 4.0 ? 1e-3 : 1e-5) << "excess " << excess;
    const double v[5] = {0.0, 0.0, 1.0 / 25.0, 0.0, 1.0 / 25.0};
    const double centre = SquareMean(v, 0.0, 0.0, response, d);
    for (int k = 0; k < 5; ++k) EXPECT_TRUE(std::isfinite(d[k])) << "parameter " << k;
    EXPECT_NEAR(centre, SquareMean(v, 0.002, 0.0, response, d), 1e-5) << "excess " << excess;
  }
}

// The response splits the blur: the optics' variance is the blur less the pixel's area and the
// crosstalk, the crosstalk a kernel that sums to 1 with the crosstalk's variance; none without.
TEST(BlobPixelModel, TheResponseSplitsTheBlur) {
  const PixelResponse plain = MakeResponse(0.5, 0.0, 0.0);
  EXPECT_NEAR(plain.optics_sd * plain.optics_sd, 0.5 - kPixelAreaVarPx2, 1e-12);
  EXPECT_EQ(plain.reach, 0);
  const PixelResponse split = MakeResponse(0.9, 0.3, 0.0);
  EXPECT_NEAR(split.optics_sd * split.optics_sd, 0.9 - kPixelAreaVarPx2 - 0.3, 1e-12);
  ASSERT_GT(split.reach, 0);
  ASSERT_EQ(split.kernel.size(), static_cast<size_t>(2 * split.reach + 1));
  double sum = 0.0, var = 0.0;
  for (int k = -split.reach; k <= split.reach; ++k) {
    sum += split.kernel[k + split.reach];
    var += k * k * split.kernel[k + split.reach];
  }
  EXPECT_NEAR(sum, 1.0, 1e-9);
  EXPECT_NEAR(var, 0.3, 0.01);
}

// The crosstalk's spreading keeps the valid part: a single bright pixel becomes the kernel's
// outer product, and a flat image stays flat.
TEST(BlobPixelModel, ConvolveSpreadsAnImpulseIntoTheKernel) {
  const std::vector<double> kernel = {0.25, 0.5, 0.25};
  const int rows = 5, cols = 5;
  std::vector<double> in(rows * cols, 0.0), across(rows * 3), out(9);
  in[2 * cols + 2] = 1.0;
  Convolve(in.data(), rows, cols, kernel, true, across.data());
  Convolve(across.data(), rows, 3, kernel, false, out.data());
  for (int row = 0; row < 3; ++row) {
    for (int col = 0; col < 3; ++col) {
      EXPECT_NEAR(out[row * 3 + col], kernel[2 - row] * kernel[2 - col], 1e-15) << row << col;
    }
  }
  std::fill(in.begin(), in.end(), 0.7);
  Convolve(in.data(), rows, cols, kernel, true, across.data());
  Convolve(across.data(), rows, 3, kernel, false, out.data());
  for (double v : out) EXPECT_NEAR(v, 0.7, 1e-15);
}

// Far from the edge of a large disc a pixel's mean is its blurred straight edge: along a pixel
// axis, the mean over the square of Phi((t + u) / sd), u uniform on [-1/2, 1/2], in closed form.
TEST(BlobPixelModel, AStraightEdgesPixelMeansAreTheBlurredSquaresIntegral) {
  const double radius = 4000.0;  // curvature 1/4000 px: its blur moves the edge by 4e-5 px
  const double v[5] = {0.0, 0.0, 1.0 / (radius * radius), 0.0, 1.0 / (radius * radius)};
  PixelResponse response;
  response.optics_sd = 0.5;
  double d[5];
  for (const double t : {-1.3, -0.6, -0.2, 0.0, 0.35, 0.8, 1.5}) {
    const double value = SquareMean(v, radius - t, 0.0, response, d);  // t px inside the edge
    double expected = 0.0;  // the square's mean of Phi, by the midpoint rule
    const int steps = 4000;
    for (int i = 0; i < steps; ++i) {
      const double u = -0.5 + (i + 0.5) / steps;
      expected += 0.5 * std::erfc(-(t + u) / (response.optics_sd * std::sqrt(2.0))) / steps;
    }
    EXPECT_NEAR(value, expected, 5e-5) << "t " << t;
  }
}

// The same with the optics' edge beyond a Gaussian's: a line spread phi(x) (1 + g He4(x) / 24) of
// excess kurtosis g (Gram-Charlier), integrated by the midpoint rule from its own density (its
// edge is the running sum of the line spread, the pixel's mean the square's mean of the edge),
// not from the closed forms the model uses. MakeResponse carries the excess as g / 24.
TEST(BlobPixelModel, AStraightEdgeBeyondAGaussianIsItsLineSpreadsIntegral) {
  const double radius = 4000.0;
  const double v[5] = {0.0, 0.0, 1.0 / (radius * radius), 0.0, 1.0 / (radius * radius)};
  for (const double excess : {-2.0, 1.5, 4.0}) {
    const PixelResponse response = MakeResponse(0.5 * 0.5 + kPixelAreaVarPx2, 0.0, 0.0, excess);
    ASSERT_NEAR(response.optics_sd, 0.5, 1e-12);
    const double sd = response.optics_sd;
    // The edge E(s) = integral of the line spread up to s, tabulated on a fine grid.
    const int steps = 20000;
    const double low = -12.0 * sd, step = 24.0 * sd / steps;
    std::vector<double> edge(steps + 1, 0.0);
    for (int i = 1; i <= steps; ++i) {
      const double x = (low + (i - 0.5) * step) / sd;
      const double he4 = x * x * x * x - 6.0 * x * x + 3.0;
      edge[i] = edge[i - 1] + std::exp(-0.5 * x * x) / std::sqrt(2.0 * kPi) *
                                  (1.0 + excess / 24.0 * he4) * step / sd;
    }
    EXPECT_NEAR(edge.back(), 1.0, 1e-9) << "excess " << excess;  // the light kept
    for (const double t : {-1.3, -0.6, -0.2, 0.0, 0.35, 0.8, 1.5}) {
      double d[5];
      const double value = SquareMean(v, radius - t, 0.0, response, d);
      double expected = 0.0;
      const int cells = 2000;
      for (int i = 0; i < cells; ++i) {
        const double s = t - 0.5 + (i + 0.5) / cells;  // the edge's distance inside the square
        const double at = (s - low) / step;
        const int j = std::clamp(static_cast<int>(at), 0, steps - 1);
        expected += (edge[j] + (at - j) * (edge[j + 1] - edge[j])) / cells;
      }
      EXPECT_NEAR(value, expected, 5e-5) << "excess " << excess << ", t " << t;
    }
  }
}

// Behind the sharpest optics the model keeps (kMinOpticsVarPx2), a disc's pixels are the disc's
// areas inside the pixels' squares (exact: testing::CircleRectArea) to within its curved edge's
// sagitta: the second moment sum r^2 m within 0.05% of the exact areas' at every phase of the
// radius (4.5..6.5 px in 1/8 px) and three centres. One straight edge over the whole square, with
// the sagitta as a Gaussian widening, swung by +-0.15% with the phase.
TEST(BlobPixelModel, ASharpDiscsPixelsAreItsAreasWhateverTheRadiusPhase) {
  PixelResponse response;
  response.optics_sd = std::sqrt(kMinOpticsVarPx2);
  double worst = 0.0;
  for (const double centre : {0.0, 0.3, 0.5}) {
    const double cx = centre, cy = -0.7 * centre;
    for (double radius = 4.5; radius <= 6.51; radius += 0.125) {
      const double v[5] = {cx, cy, 1.0 / (radius * radius), 0.0, 1.0 / (radius * radius)};
      double model = 0.0, exact = 0.0, d[5];
      for (int y = -9; y <= 9; ++y) {
        for (int x = -9; x <= 9; ++x) {
          const double r2 = (x - cx) * (x - cx) + (y - cy) * (y - cy);
          model += r2 * SquareMean(v, x, y, response, d);
          exact += r2 * testing::CircleRectArea(radius, x - 0.5 - cx, x + 0.5 - cx, y - 0.5 - cy,
                                                y + 0.5 - cy);
        }
      }
      worst = std::max(worst, std::abs(model / exact - 1.0));
      EXPECT_NEAR(model / exact, 1.0, 5e-4) << "radius " << radius << ", centre " << centre;
    }
  }
  std::printf("sharp disc: second moment within %.4f%% of the exact areas'\n", 100.0 * worst);
}

}  // namespace
}  // namespace blob_model
}  // namespace irdist
