// FitBlurSplit (estimator/blur_split.cc, declared in blob_fit.h): which calibration frames take
// part, and the split and the blur's offset found on frames rendered by the independent
// spectral renderer (tests/estimator/disc_spectrum.h) with a known optics and crosstalk.
#include <gtest/gtest.h>

#include <boost/math/tools/minima.hpp>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "estimator/blob_fit.h"
#include "estimator/blur_model.h"
#include "estimator/features.h"
#include "tests/estimator/disc_spectrum.h"
#include "tests/estimator/pixel_responses.h"
#include "tests/estimator/spectrum_frame.h"

namespace irdist {
namespace {

// A 16-bit calibration frame of a round disc of `radius` px: blurred by `optics_px` before the
// pixels and by a sampled Gaussian of `crosstalk_px` after them; given its true total blur
// (optics, pixel area, crosstalk) unless the caller changes it.
CrosstalkFrame Frame(double radius, double optics_px, double crosstalk_px) {
  testing::DiscBlob blob;
  blob.cx = 23.3;
  blob.cy = 23.6;
  blob.a = blob.b = radius;
  blob.optics_sigma_px = optics_px;
  blob.crosstalk_sigma_px = crosstalk_px;
  CrosstalkFrame frame = testing::SpectrumFrame16(blob);
  frame.blur_var_px2 =
      optics_px * optics_px + kPixelAreaVarPx2 + testing::CrosstalkVariance(crosstalk_px);
  return frame;
}

// No frames, or none usable (no blob, or a blur not above the pixel's own area by 0.05 px^2):
// nothing split, no offset, zero frames.
TEST(FitBlurSplit, NoUsableFramesGiveNoSplit) {
  const BlurSplit none = FitBlurSplit({});
  EXPECT_EQ(none.frames, 0);
  EXPECT_EQ(none.crosstalk_var_px2, 0.0);
  EXPECT_EQ(none.blur_offset_px2, 0.0);
  CrosstalkFrame sharp = Frame(6.0, 0.3, 0.0);
  sharp.blur_var_px2 = kPixelAreaVarPx2 + 0.04;
  CrosstalkFrame blind = Frame(6.0, 0.5, 0.0);
  blind.features.blob_found = false;
  CrosstalkFrame saturated = Frame(6.0, 0.5, 0.0);
  saturated.features.saturated_pixels = 2;
  const BlurSplit split = FitBlurSplit({sharp, blind, saturated});
  EXPECT_EQ(split.frames, 0);
  EXPECT_EQ(split.crosstalk_var_px2, 0.0);
  EXPECT_EQ(split.crosstalk_lattice_share, 0.0);
  EXPECT_EQ(split.blur_offset_px2, 0.0);
  EXPECT_EQ(split.blur_offset_u_px2, 0.0);
}

// Optics alone (0.5 px, no crosstalk), each frame given its true blur: no crosstalk is found and
// the blur needs no offset. Only the usable frames take part.
TEST(FitBlurSplit, OpticsAloneGiveNoCrosstalk) {
  std::vector<CrosstalkFrame> frames = {Frame(5.0, 0.5, 0.0), Frame(7.7, 0.5, 0.0)};
  frames[0].d_mm = 2000.0;
  frames[1].d_mm = 1300.0;
  CrosstalkFrame unusable = Frame(6.0, 0.5, 0.0);
  unusable.features.touches_border = true;
  frames.push_back(unusable);
  const BlurSplit split = FitBlurSplit(frames);
  EXPECT_EQ(split.frames, 2);
  EXPECT_LT(split.crosstalk_var_px2, 0.03);
  for (const CrosstalkFrame& f : {frames[0], frames[1]}) {
    EXPECT_NEAR(split.OffsetPx2(1000.0 / f.d_mm), 0.0, 0.01) << "at " << f.d_mm << " mm";
  }
}

// Sharp optics (0.3 px) and a crosstalk of 0.8 px after the pixels: the split gives the
// crosstalk's variance, not the optics', out of the same total blur.
TEST(FitBlurSplit, SharpOpticsShowTheCrosstalk) {
  const std::vector<CrosstalkFrame> frames = {Frame(5.0, 0.3, 0.8), Frame(8.0, 0.3, 0.8)};
  const BlurSplit split = FitBlurSplit(frames);
  EXPECT_EQ(split.frames, 2);
  EXPECT_NEAR(split.crosstalk_var_px2, testing::CrosstalkVariance(0.8), 0.03);
  EXPECT_LT(split.crosstalk_lattice_share, 0.25);  // a sampled Gaussian, not a random walk
}

// Frames given a blur 0.05 px^2 too small (optics alone, 0.5 px): the offset found adds it back
// within 0.01 px^2, and the optics keep at least their minimum (kMinOpticsVarPx2) of the blur so
// corrected beside the crosstalk and the pixel's area.
TEST(FitBlurSplit, AGivenBlurTooSmallIsOffsetBack) {
  std::vector<CrosstalkFrame> frames = {Frame(5.0, 0.5, 0.0), Frame(8.0, 0.5, 0.0)};
  for (CrosstalkFrame& f : frames) f.blur_var_px2 -= 0.05;
  const BlurSplit split = FitBlurSplit(frames);
  EXPECT_EQ(split.frames, 2);
  EXPECT_NEAR(split.blur_offset_px2, 0.05, 0.01);
  const double corrected = frames[0].blur_var_px2 + split.blur_offset_px2;
  EXPECT_LE(split.crosstalk_var_px2, corrected - kPixelAreaVarPx2 - kMinOpticsVarPx2 + 1e-9);
}

// A blur given 0.03 px^2 too large on every frame (one distance unknown: a constant offset):
// the offset found takes it back within 0.01 px^2.
TEST(FitBlurSplit, AGivenBlurTooLargeIsOffsetBack) {
  std::vector<CrosstalkFrame> frames = {Frame(5.0, 0.5, 0.0), Frame(7.0, 0.5, 0.0)};
  for (CrosstalkFrame& f : frames) f.blur_var_px2 += 0.03;
  const BlurSplit split = FitBlurSplit(frames);
  EXPECT_EQ(split.blur_offset_u_px2, 0.0);  // no distances: no slope
  EXPECT_NEAR(split.blur_offset_px2, -0.03, 0.01);
}

// A sensor whose blur is all after the pixels (a 1 px Gaussian sampled on them, cut at 4 sd; no
// optics), noise free, its frames given a blur 0.01-0.05 px^2 short of it and not as a line in
// 1000 / d (the cumulants' blur short of such a sensor's, as the virtual rig's reads it): the
// split finds the crosstalk within 0.01 px^2 (0.999 for 1.000), a sampled Gaussian. Held at the
// room the least given blur left it (FitBlurSplit without AlongTheKink) it read 0.976.
TEST(FitBlurSplit, AllTheBlurAfterThePixelsIsFoundPastTheGivenBlursRoom) {
  const double truth = testing::KernelVariance(testing::AfterPixelsKernel());
  std::vector<CrosstalkFrame> frames;
  FeatureOptions options;
  options.window_side_px = 36;
  const double short_px2[] = {0.01, 0.05, 0.03};  // at 1500, 2100 and 3000 mm
  for (int k = 0; k < 3; ++k) {
    const double d_mm = std::vector<double>{1500.0, 2100.0, 3000.0}[k];
    for (const double phase : {0.0, 0.37}) {
      CrosstalkFrame f;
      f.image = testing::DiscFrame12(22.0 + phase, 21.8 - 0.5 * phase, 9.1 * 1500.0 / d_mm,
                                     testing::PixelResponseKind::kAllBlurAfter, 44);
      f.features = ComputeFeatures(f.image, 12, options);
      f.blur_var_px2 = kPixelAreaVarPx2 + truth - short_px2[k];
      f.d_mm = d_mm;
      frames.push_back(f);
    }
  }
  const BlurSplit split = FitBlurSplit(frames);
  EXPECT_EQ(split.frames, 6);
  std::printf("crosstalk %.4f px^2 (true %.4f), lattice share %.3f\n", split.crosstalk_var_px2,
              truth, split.crosstalk_lattice_share);
  EXPECT_NEAR(split.crosstalk_var_px2, truth, 0.01);
  EXPECT_LT(split.crosstalk_lattice_share, 0.25);  // a sampled Gaussian, not a random walk
}

// A 16-bit frame of a lens with veiling glare: a disc of `radius` px whose light is 97% in a
// 0.75 px Gaussian and 3% in a halo of sd 8 px (both before the pixels), 96 px wide, at `d_mm`,
// given the blur its cumulants read (as a calibration knows it).
CrosstalkFrame GlareFrame(double radius, double d_mm) {
  testing::DiscBlob blob;
  blob.cx = 47.3;
  blob.cy = 47.6;
  blob.a = blob.b = radius;
  blob.optics_sigma_px = 0.75;
  const cv::Mat1d core = testing::RenderDiscSpectrum(blob, 96);
  blob.optics_sigma_px = 8.0;
  const cv::Mat1d halo = testing::RenderDiscSpectrum(blob, 96);
  CrosstalkFrame frame;
  frame.image = testing::DiscFrame16(0.97 * core + 0.03 * halo, 30000.0, 1000.0);
  frame.bit_depth = 16;
  FeatureOptions options;
  options.window_side_px = 64;
  frame.features = ComputeFeatures(frame.image, 16, options);
  frame.blur_var_px2 = frame.features.blur_var_px2;  // the cumulants', the halo's tail in it
  frame.d_mm = d_mm;
  return frame;
}

// The blur (px^2) at which the frame's one-pass blob fit at `crosstalk` fits best (what the blob
// fit's own blur, estimator/refocus.h, finds when measuring), searched within +-0.5 px^2.
double OwnBestBlur(const CrosstalkFrame& f, const Crosstalk& crosstalk) {
  const auto cost = [&](double blur) {
    const BlobFitResult fit = FitBlobPasses(f.image, f.bit_depth, f.features, blur, crosstalk, 1);
    return fit.ok ? fit.read_weighted_chi2 * fit.pixels : std::numeric_limits<double>::infinity();
  };
  boost::uintmax_t iterations = 60;
  return boost::math::tools::brent_find_minima(cost, f.blur_var_px2 - 0.5, f.blur_var_px2 + 0.5,
                                               20, iterations)
      .first;
}

// A lens outside the blob fit's family (the glare above): the split and the blur's offset trade
// along a valley, and whatever split is kept, the offset's line must be each frame's own best
// blur at that split, or a bracket of the very lens calibrated reads a blur away from its
// calibration (a halo lens's read -6% on the virtual rig, flagged and measured as refocused,
// -0.4% in distance). Each frame within 0.03 px^2 of the line (a line in 1/d is the offset's
// form; this lens's own blurs bend off it by 0.02), and no bias across them.
TEST(FitBlurSplit, TheOffsetIsEachFramesOwnBestBlurAtTheSplitKept) {
  const std::vector<CrosstalkFrame> frames = {GlareFrame(9.0, 1500.0), GlareFrame(6.75, 2000.0),
                                              GlareFrame(5.4, 2500.0), GlareFrame(4.5, 3000.0)};
  const BlurSplit split = FitBlurSplit(frames);
  ASSERT_EQ(split.frames, 4);
  const Crosstalk kept = CrosstalkOf(split);
  double mean_miss_px2 = 0.0;
  for (const CrosstalkFrame& f : frames) {
    const double offset = split.OffsetPx2(1000.0 / f.d_mm);
    const double miss_px2 = f.blur_var_px2 + offset - OwnBestBlur(f, kept);
    EXPECT_LT(std::fabs(miss_px2), 0.03) << "at " << f.d_mm << " mm";
    mean_miss_px2 += miss_px2 / static_cast<double>(frames.size());
  }
  EXPECT_LT(std::fabs(mean_miss_px2), 0.015);  // before: 0.054 (0.040-0.066 each)
}

}  // namespace
}  // namespace irdist
