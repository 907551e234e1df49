// The blob fit's own blur (estimator/refocus.h): each frame's blur fitted with its size by the
// blob family the calibration used, on frames of the independent renderer (disc_spectrum.h), and
// a bracket's joint blur from its frames.
#include "estimator/refocus.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <random>
#include <vector>

#include "estimator/blob_fit.h"
#include "estimator/blur_model.h"
#include "tests/estimator/disc_spectrum.h"
#include "tests/estimator/pixel_responses.h"

namespace irdist {
namespace {

constexpr double kRadiusPx = 7.0;

// A 16-bit frame of a disc of kRadiusPx behind optics of `optics_px` (sd), centre at a sub-pixel
// phase; with `rng`, shot noise (gain 1 DN/e-) and 10 DN of read noise.
cv::Mat DiscFrame(double optics_px, double amplitude, std::mt19937_64* rng) {
  testing::DiscBlob blob;
  blob.cx = 23.3;
  blob.cy = 23.6;
  blob.a = blob.b = kRadiusPx;
  blob.optics_sigma_px = optics_px;
  cv::Mat frame = testing::DiscFrame16(testing::RenderDiscSpectrum(blob, 48), amplitude, 200.0);
  if (rng == nullptr) return frame;
  std::normal_distribution<double> unit(0.0, 1.0);
  for (int row = 0; row < frame.rows; ++row) {
    for (int col = 0; col < frame.cols; ++col) {
      const double v = frame.at<std::uint16_t>(row, col);
      const double noisy = v + std::sqrt(v + 100.0) * unit(*rng);
      frame.at<std::uint16_t>(row, col) =
          static_cast<std::uint16_t>(std::clamp(std::round(noisy), 0.0, 65535.0));
    }
  }
  return frame;
}

// The CPU time spent in MeasureOwnBlur (reported, never asserted).
double own_blur_cpu_s = 0.0;

// The frame's features as the app makes them with a model whose calibrated blob-fit blur is
// `given_px2` (RefineWithBlobFit's replacement), then its own blur (MeasureOwnBlur).
Features OwnBlurOf(const cv::Mat& frame, double given_px2, bool* measured) {
  FeatureOptions options;
  options.window_side_px = 40;
  const Features start = ComputeFeatures(frame, 16, options);
  Features f = start;
  const BlobFitResult fit = FitBlob(frame, 16, start, given_px2);
  EXPECT_TRUE(fit.ok);
  f.moment_major_var_px2 = fit.major_var_px2 + given_px2;
  f.moment_minor_var_px2 = fit.minor_var_px2 + given_px2;
  f.size_blur_var_px2 = given_px2;
  const std::clock_t before = std::clock();
  *measured = MeasureOwnBlur(frame, 16, CalibrationModel(), start, &f);
  own_blur_cpu_s += static_cast<double>(std::clock() - before) / CLOCKS_PER_SEC;
  return f;
}

double BlurVar(double optics_px) { return optics_px * optics_px + kPixelAreaVarPx2; }

// A sensor whose blur is all after the pixels (a 1 px Gaussian sampled on them, no optics: the
// calibration's crosstalk is all of it, the optics at their floor, on the crosstalk's kink,
// blob_fit.h RoomFor) reads its own blur at the calibrated one: noise free within 0.002 px^2,
// and every one of 12 noisy 12-bit frames measured, their mean within 3 of its standard errors
// of the truth. A search held at the kink could not reach the truth (it lies 0.0004 px^2 below
// the kink) and lost the noisy frames whose noise asks for less blur.
TEST(Refocus, ASensorsBlurAllAfterThePixelsReadsAsCalibrated) {
  CalibrationModel model;
  model.blur_calibration.crosstalk_var_px2 = testing::KernelVariance(testing::AfterPixelsKernel());
  const double given_px2 = kPixelAreaVarPx2 + model.blur_calibration.crosstalk_var_px2;
  FeatureOptions options;
  options.window_side_px = 36;
  std::mt19937_64 rng(11);
  double sum = 0.0, sum_se2 = 0.0;
  const int noisy = 12;
  for (int i = 0; i <= noisy; ++i) {
    const cv::Mat frame = testing::DiscFrame12(
        22.3, 21.8, 6.6, testing::PixelResponseKind::kAllBlurAfter, 44, i == 0 ? nullptr : &rng);
    const Features start = ComputeFeatures(frame, 12, options);
    const BlobFitResult fit =
        FitBlob(frame, 12, start, given_px2, CrosstalkOf(model.blur_calibration));
    ASSERT_TRUE(fit.ok);
    Features f = start;
    f.moment_major_var_px2 = fit.major_var_px2 + given_px2;
    f.moment_minor_var_px2 = fit.minor_var_px2 + given_px2;
    f.size_blur_var_px2 = given_px2;
    ASSERT_TRUE(MeasureOwnBlur(frame, 12, model, start, &f)) << "frame " << i;
    if (i == 0) {
      EXPECT_NEAR(f.own_blur_var_px2, given_px2, 0.002);
      continue;
    }
    sum += f.own_blur_var_px2 - given_px2;
    sum_se2 += f.own_blur_se_px2 * f.own_blur_se_px2;
  }
  EXPECT_LT(std::abs(sum / noisy), 3.0 * std::sqrt(sum_se2) / noisy);
}

// The lens 30% wider than calibrated (0.91 px against 0.7 px): the frame's own blur is the
// rendered one, not the calibrated one it was given, and the size at it is the disc's (a^2/4),
// where the size at the calibrated blur is 1.6% too large.
TEST(Refocus, AFramesOwnBlurIsTheRenderedOneAndItsSizeTheDiscs) {
  const cv::Mat frame = DiscFrame(0.91, 30000.0, nullptr);
  bool measured = false;
  const Features f = OwnBlurOf(frame, BlurVar(0.7), &measured);
  ASSERT_TRUE(measured);
  EXPECT_NEAR(f.own_blur_var_px2, BlurVar(0.91), 0.01);
  EXPECT_GT(f.own_blur_se_px2, 0.0);
  const double disc_px2 = kRadiusPx * kRadiusPx / 4.0;
  const double at_calibrated = f.moment_major_var_px2 - f.size_blur_var_px2;
  EXPECT_GT(std::abs(at_calibrated / disc_px2 - 1.0), 0.01);  // what the estimate saw before
  const Features refocused = AtBlur(f, f.own_blur_var_px2);
  EXPECT_NEAR((refocused.moment_major_var_px2 - f.size_blur_var_px2) / disc_px2, 1.0, 0.002);
  EXPECT_NEAR((refocused.moment_minor_var_px2 - f.size_blur_var_px2) / disc_px2, 1.0, 0.002);
  // The slope carries the size along the blur: AtBlur 0.05 px^2 away moves the size as the
  // one-pass fit (the cost the blur is measured on) refitted there moves it (a noise-free frame's
  // two-pass fit is not the yardstick: its second pass weights by the residuals of a wrong blur).
  FeatureOptions options;
  options.window_side_px = 40;
  const Features start = ComputeFeatures(frame, 16, options);
  const BlobFitResult at = FitBlobPasses(frame, 16, start, f.own_blur_var_px2, {}, 1);
  const BlobFitResult near = FitBlobPasses(frame, 16, start, f.own_blur_var_px2 - 0.05, {}, 1);
  ASSERT_TRUE(at.ok && near.ok);
  const double refit = near.raw_major_var_px2 - at.raw_major_var_px2;
  const Features moved = AtBlur(f, f.own_blur_var_px2 - 0.05);
  EXPECT_GT(std::abs(refit), 1e-3);  // the size moves with the blur: a slope to test
  EXPECT_NEAR(moved.moment_major_var_px2 - refocused.moment_major_var_px2, refit,
              0.05 * std::abs(refit));
}

// On noisy frames the own blur scatters as its standard error says (curvature of the cost,
// scaled by its value per pixel), around the rendered blur: given the calibration's blur (the
// usual case: one profile of the cost around it) and given one 26% smaller (a focus change:
// Newton's steps).
TEST(Refocus, AFramesOwnBlurScattersAsItsStandardErrorSays) {
  for (const double given_optics_px : {0.8, 0.7}) {
    std::mt19937_64 rng(7);
    std::vector<double> blur, se;
    own_blur_cpu_s = 0.0;
    for (int i = 0; i < 16; ++i) {
      bool measured = false;
      const Features f = OwnBlurOf(DiscFrame(0.8, 3000.0, &rng), BlurVar(given_optics_px),
                                   &measured);
      ASSERT_TRUE(measured) << i;
      blur.push_back(f.own_blur_var_px2);
      se.push_back(f.own_blur_se_px2);
    }
    double mean = 0.0, sd = 0.0;
    for (double b : blur) mean += b / blur.size();
    for (double b : blur) sd += (b - mean) * (b - mean) / (blur.size() - 1);
    sd = std::sqrt(sd);
    double mean_se = 0.0;
    for (double s : se) mean_se += s / se.size();
    std::printf("given %.1f px: own blur %.4f px^2 (true %.4f), sd %.4f, mean se %.4f; %.1f ms "
                "of CPU a frame\n",
                given_optics_px, mean, BlurVar(0.8), sd, mean_se,
                1000.0 * own_blur_cpu_s / blur.size());
    EXPECT_NEAR(mean, BlurVar(0.8), 4.0 * sd / std::sqrt(blur.size()) + 0.005);
    EXPECT_GT(sd / mean_se, 0.6);
    EXPECT_LT(sd / mean_se, 1.6);
  }
}

// Without the blob fit's refined blob (no calibrated blur given) nothing is measured.
TEST(Refocus, NothingIsMeasuredWithoutTheCalibratedBlur) {
  const cv::Mat frame = DiscFrame(0.7, 30000.0, nullptr);
  FeatureOptions options;
  options.window_side_px = 40;
  const Features start = ComputeFeatures(frame, 16, options);
  Features f = start;
  EXPECT_FALSE(MeasureOwnBlur(frame, 16, CalibrationModel(), start, &f));
  EXPECT_TRUE(std::isnan(f.own_blur_var_px2));
  EXPECT_EQ(AtBlur(f, 1.0).moment_major_var_px2, f.moment_major_var_px2);
}

Features WithOwnBlur(double own_px2, double se_px2, double given_px2) {
  Features f;
  f.own_blur_var_px2 = own_px2;
  f.own_blur_se_px2 = se_px2;
  f.size_blur_var_px2 = given_px2;
  return f;
}

// A bracket's blur is its frames' joint minimum: their inverse-variance mean, its standard error
// grown where the frames disagree beyond their errors; frames without an own blur take no part.
TEST(Refocus, ABracketsBlurIsItsFramesJointMinimum) {
  const Features a = WithOwnBlur(1.0, 0.01, 0.8), b = WithOwnBlur(1.1, 0.02, 0.9);
  const Features none;
  BracketBlur blur = FitBracketBlur({&a, &b, &none, nullptr});
  EXPECT_EQ(blur.frames, 2);
  EXPECT_NEAR(blur.blur_var_px2, (1.0 / 1e-4 + 1.1 / 4e-4) / (1.0 / 1e-4 + 1.0 / 4e-4), 1e-12);
  EXPECT_NEAR(blur.calibrated_px2, (0.8 / 1e-4 + 0.9 / 4e-4) / (1.0 / 1e-4 + 1.0 / 4e-4), 1e-12);
  // 0.1 apart at errors 0.01 and 0.02: chi2 = 0.01 / (1e-4 + 4e-4) = 20 for 1 dof.
  EXPECT_NEAR(blur.chi2_per_dof, 20.0, 1e-9);
  EXPECT_NEAR(blur.se_px2, std::sqrt(20.0 / (1.0 / 1e-4 + 1.0 / 4e-4)), 1e-12);
  const Features c = WithOwnBlur(1.0, 0.01, 0.8);
  blur = FitBracketBlur({&a, &c});
  EXPECT_NEAR(blur.se_px2, 0.01 / std::sqrt(2.0), 1e-12);  // agreeing frames: no growth
  EXPECT_EQ(FitBracketBlur({&none}).frames, 0);
}

}  // namespace
}  // namespace irdist
