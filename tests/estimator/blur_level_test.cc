// The blob fit's blur level and split refined on every calibration frame (estimator/blur_level.h):
// BlurLevelLine (the line of the frames' own best blurs refitted on all of them, an outlier left
// out, the split's own line kept when too few frames take part), ProfileBlobSplit's gradient and
// BlurSplitRefiner's passes.
#include "estimator/blur_level.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "estimator/blob_fit.h"
#include "estimator/blur_model.h"
#include "estimator/features.h"
#include "tests/estimator/disc_spectrum.h"
#include "tests/estimator/pixel_responses.h"
#include "tests/estimator/spectrum_frame.h"

namespace irdist {
namespace {

// A 16-bit calibration frame at `d_mm` of a round disc of 9 px x 1500 mm / d behind `optics_px` of
// optics (no crosstalk), at a sub-pixel centre that moves with d, given its true blur plus
// `given_error_px2` (a cumulants' blur that misses).
CrosstalkFrame Frame(double d_mm, double optics_px, double given_error_px2) {
  testing::DiscBlob blob;
  blob.cx = 23.3 + 0.37 * std::fmod(d_mm / 100.0, 1.0);
  blob.cy = 23.6 - 0.29 * std::fmod(d_mm / 70.0, 1.0);
  blob.a = blob.b = 9.0 * 1500.0 / d_mm;
  blob.optics_sigma_px = optics_px;
  CrosstalkFrame frame = testing::SpectrumFrame16(blob);
  frame.blur_var_px2 = optics_px * optics_px + kPixelAreaVarPx2 + given_error_px2;
  frame.d_mm = d_mm;
  return frame;
}

std::vector<CrosstalkFrame> Frames(double given_error_px2) {
  std::vector<CrosstalkFrame> frames;
  for (double d_mm = 1500.0; d_mm <= 3000.0; d_mm += 150.0) {
    frames.push_back(Frame(d_mm, 0.5, given_error_px2));
  }
  return frames;
}

// Offsets at four distances (u = 1000 / d over 1.5-3 m), 16 a distance with a frame's scatter of
// 0.009 px^2 (weights 1 / se^2), on `truth`.
std::vector<OffsetPoint> OffsetPoints(double o0, double o1, double o2, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.009);
  std::vector<OffsetPoint> points;
  for (const double d_mm : {1500.0, 2000.0, 2500.0, 3000.0}) {
    const double u = 1000.0 / d_mm;
    for (int i = 0; i < 16; ++i) {
      points.push_back({u, o0 + (o1 + o2 * u) * u + noise(rng), 1.0 / (0.009 * 0.009)});
    }
  }
  return points;
}

// A lens whose cumulants' blur bends with the disc's size unlike the fit's own (the phase sweep's
// Airy lens: the offset rises 0.86 px^2 over the range, its middle 0.17 px^2 off the chord) is
// followed within 0.005 px^2 at every distance; a straight offset keeps no bend at all (seeds
// 1-20); points at two distances make a line, at one a constant.
TEST(FitOffsetCurve, ABendOutOfTheScatterIsKeptAndALinesIsNot) {
  double o0 = 0.0, o1 = 0.0, o2 = 0.0;
  ASSERT_TRUE(FitOffsetCurve(OffsetPoints(-3.877, 8.832, -6.248, 1), &o0, &o1, &o2));
  for (const double u : {1.0 / 3.0, 0.5, 2.0 / 3.0}) {
    EXPECT_NEAR(o0 + (o1 + o2 * u) * u, -3.877 + (8.832 - 6.248 * u) * u, 0.005) << u;
  }
  for (unsigned seed = 1; seed <= 20; ++seed) {
    ASSERT_TRUE(FitOffsetCurve(OffsetPoints(0.02, -0.03, 0.0, seed), &o0, &o1, &o2));
    EXPECT_EQ(o2, 0.0) << seed;
    EXPECT_NEAR(o0 + o1 * 0.5, 0.02 - 0.03 * 0.5, 0.005) << seed;
  }
  const std::vector<OffsetPoint> two = {{0.5, 0.1, 1.0}, {0.5, 0.12, 1.0}, {0.6, 0.2, 1.0}};
  ASSERT_TRUE(FitOffsetCurve(two, &o0, &o1, &o2));
  EXPECT_NEAR(o1, 0.9, 1e-9);
  EXPECT_EQ(o2, 0.0);
  ASSERT_TRUE(FitOffsetCurve({{0.5, 0.1, 1.0}, {0.5, 0.2, 1.0}}, &o0, &o1, &o2));
  EXPECT_NEAR(o0, 0.15, 1e-12);
  EXPECT_EQ(o1, 0.0);
  EXPECT_FALSE(FitOffsetCurve({{0.5, 0.1, 0.0}}, &o0, &o1, &o2));
}

// Frames given a blur 0.05 px^2 too small at every distance, and a split whose line missed it
// (none): the refitted line adds it back within 0.005 px^2 at both ends of the range.
TEST(BlurLevelLine, TheLineIsTheFramesOwnBestBlur) {
  BlurLevelLine level{BlurSplit{}};
  for (const CrosstalkFrame& f : Frames(-0.05)) EXPECT_TRUE(level.Add(f)) << f.d_mm;
  const BlurSplit fitted = level.Fitted();
  EXPECT_EQ(fitted.level_frames, 11);
  for (const double d_mm : {1500.0, 3000.0}) {
    EXPECT_NEAR(fitted.OffsetPx2(1000.0 / d_mm), 0.05, 0.005) << d_mm;
  }
}

// One frame of a blurrier lens (0.8 px: its own best blur 0.39 px^2 above the others') is left
// out: the line is the others' within 0.005 px^2.
TEST(BlurLevelLine, AnOutlierFrameIsLeftOut) {
  std::vector<CrosstalkFrame> frames = Frames(0.0);
  BlurLevelLine clean{BlurSplit{}}, with_outlier{BlurSplit{}};
  for (const CrosstalkFrame& f : frames) clean.Add(f);
  frames[4] = Frame(frames[4].d_mm, 0.8, 0.8 * 0.8 - 0.5 * 0.5);
  frames[4].blur_var_px2 = 0.5 * 0.5 + kPixelAreaVarPx2;  // given the others' blur
  for (const CrosstalkFrame& f : frames) with_outlier.Add(f);
  const BlurSplit a = clean.Fitted(), b = with_outlier.Fitted();
  EXPECT_EQ(b.level_frames, a.level_frames - 1);
  for (const double d_mm : {1500.0, 3000.0}) {
    const double u = 1000.0 / d_mm;
    EXPECT_NEAR(b.OffsetPx2(u), a.OffsetPx2(u), 0.005) << d_mm;
  }
}

// Fewer than kMinBlurLevelFrames frames, or frames without a blob: the split's own line is kept.
TEST(BlurLevelLine, TooFewFramesKeepTheSplitsLine) {
  BlurSplit split;
  split.blur_offset_px2 = 0.02;
  split.blur_offset_u_px2 = -0.01;
  BlurLevelLine level(split);
  std::vector<CrosstalkFrame> frames = Frames(-0.05);
  frames.resize(kMinBlurLevelFrames - 1);
  for (const CrosstalkFrame& f : frames) level.Add(f);
  CrosstalkFrame blind = Frames(0.0)[0];
  blind.features.blob_found = false;
  EXPECT_FALSE(level.Add(blind));
  const BlurSplit kept = level.Fitted();
  EXPECT_EQ(kept.level_frames, 0);
  EXPECT_EQ(kept.blur_offset_px2, 0.02);
  EXPECT_EQ(kept.blur_offset_u_px2, -0.01);
}

// A frame of a sharp lens (0.3 px) with 0.6 px of crosstalk (a sampled Gaussian) at `d_mm`,
// given its true blur.
CrosstalkFrame SharpFrame(double d_mm) {
  testing::DiscBlob blob;
  blob.cx = 23.3 + 0.37 * std::fmod(d_mm / 100.0, 1.0);
  blob.cy = 23.6 - 0.29 * std::fmod(d_mm / 70.0, 1.0);
  blob.a = blob.b = 9.0 * 1500.0 / d_mm;
  blob.optics_sigma_px = 0.3;
  blob.crosstalk_sigma_px = 0.6;
  CrosstalkFrame frame = testing::SpectrumFrame16(blob);
  frame.blur_var_px2 = 0.09 + kPixelAreaVarPx2 + testing::CrosstalkVariance(0.6);
  frame.d_mm = d_mm;
  return frame;
}

// The one-pass cost FitBlurSplit sums, as a function of the blur and the crosstalk's variance.
double OnePassCost(const CrosstalkFrame& f, double blur, double crosstalk) {
  const BlobFitResult fit = FitBlobPasses(f.image, f.bit_depth, f.features, blur, {crosstalk}, 1);
  return fit.read_weighted_chi2 * fit.pixels;
}

// ProfileBlobSplit's gradient is half the one-pass cost's slope in the blur and in the
// crosstalk's variance (the disc refitted at each: central differences of 0.01 px^2), within 10%,
// away from the split's minimum (the blur 0.05 px^2 and the crosstalk 0.1 px^2 off).
TEST(ProfileBlobSplit, ItsGradientIsTheCostsSlope) {
  const CrosstalkFrame f = SharpFrame(2000.0);
  const double blur = f.blur_var_px2 + 0.05, crosstalk = testing::CrosstalkVariance(0.6) - 0.1;
  const BlobSplitProfile p = ProfileBlobSplit(f.image, f.bit_depth, f.features, blur, {crosstalk});
  ASSERT_TRUE(p.ok);
  const double h = 0.01;
  const double along_blur =
      (OnePassCost(f, blur + h, crosstalk) - OnePassCost(f, blur - h, crosstalk)) / (2.0 * h);
  const double along_crosstalk =
      (OnePassCost(f, blur, crosstalk + h) - OnePassCost(f, blur, crosstalk - h)) / (2.0 * h);
  EXPECT_NEAR(2.0 * p.gradient[0], along_blur, 0.1 * std::fabs(along_blur));
  EXPECT_NEAR(2.0 * p.gradient[1], along_crosstalk, 0.1 * std::fabs(along_crosstalk));
  EXPECT_GT(p.curvature[0][0], 0.0);
  EXPECT_GT(p.curvature[1][1], 0.0);
  EXPECT_NEAR(p.cost, OnePassCost(f, blur, crosstalk), 1e-3 * p.cost);
}

// Started from a split 0.1 px^2 of crosstalk short and a blur level 0.03 px^2 low, the refinement
// on the frames (RefineBlurSplit: the Gauss-Newton passes, then the level's line) brings the
// crosstalk within 0.03 px^2 of the lens's and the blur within 0.005 px^2 at both ends.
TEST(BlurSplitRefiner, ASplitOffComesBackToTheFrames) {
  std::vector<CrosstalkFrame> frames;
  for (double d_mm = 1500.0; d_mm <= 3000.0; d_mm += 150.0) frames.push_back(SharpFrame(d_mm));
  BlurSplit start;
  start.crosstalk_var_px2 = testing::CrosstalkVariance(0.6) - 0.1;
  start.blur_offset_px2 = -0.03;
  const BlurSplit refined = RefineBlurSplit(start, [&](const auto& use) {
    for (const CrosstalkFrame& f : frames) use(f);
  });
  EXPECT_NEAR(refined.crosstalk_var_px2, testing::CrosstalkVariance(0.6), 0.03);
  for (const double d_mm : {1500.0, 3000.0}) {
    EXPECT_NEAR(refined.OffsetPx2(1000.0 / d_mm), 0.0, 0.005) << d_mm;
  }
  EXPECT_EQ(refined.level_frames, static_cast<int>(frames.size()));
}

// A sensor whose blur is all after the pixels (a 1 px Gaussian sampled on them, no optics) has its
// truth on the crosstalk's kink, where the optics reach their floor (blob_fit.h RoomFor). Given
// its true blur and crosstalk, every one of 64 noisy 12-bit frames (8 distances over 1.5-3 m,
// random sub-pixel centres) takes part and the level's line is the truth within 0.003 px^2 at
// 2.25 m and 0.005 at the ends (seeds 3-8: -0.0011..+0.0019 at 2.25 m; this seed's 3, within
// 0.001 at all three). A search held at the kink lost the 35-43 frames whose noise asks for
// less blur (held on the search's edge) and read the rest +0.005..+0.008 px^2 at 2.25 m, which
// swings the size by about 0.05% with the edge's phase (docs/estimator.md "Pixel responses
// outside the model").
TEST(BlurLevelLine, ASensorsBlurAllAfterThePixelsIsNotCensoredAtTheKink) {
  const double crosstalk = testing::KernelVariance(testing::AfterPixelsKernel());
  BlurSplit truth;
  truth.crosstalk_var_px2 = crosstalk;
  BlurLevelLine level(truth);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> phase(-0.5, 0.5);
  FeatureOptions options;
  options.window_side_px = 36;
  for (double d_mm = 1500.0; d_mm <= 3000.0 + 1e-9; d_mm += 1500.0 / 7.0) {
    for (int k = 0; k < 8; ++k) {
      const double cx = 22.0 + phase(rng), cy = 22.0 + phase(rng);
      CrosstalkFrame f;
      f.image = testing::DiscFrame12(cx, cy, 9.1 * 1500.0 / d_mm,
                                     testing::PixelResponseKind::kAllBlurAfter, 44, &rng);
      f.features = ComputeFeatures(f.image, 12, options);
      f.blur_var_px2 = kPixelAreaVarPx2 + crosstalk;
      f.d_mm = d_mm;
      EXPECT_TRUE(level.Add(f)) << d_mm;
    }
  }
  const BlurSplit fitted = level.Fitted();
  EXPECT_GE(fitted.level_frames, 62);
  for (const double d_mm : {1500.0, 2250.0, 3000.0}) {
    const double level_px2 = fitted.OffsetPx2(1000.0 / d_mm);
    EXPECT_NEAR(level_px2, 0.0, d_mm == 2250.0 ? 0.003 : 0.005) << d_mm;
  }
}

}  // namespace
}  // namespace irdist
