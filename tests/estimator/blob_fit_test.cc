#include "estimator/blob_fit.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <opencv2/imgproc.hpp>
#include <random>
#include <vector>

#include "base/pi.h"
#include "tests/estimator/disc_spectrum.h"
#include "tests/estimator/spectrum_frame.h"

namespace irdist {
namespace {

constexpr int kSide = 96;
constexpr int kSuper = 16;

// A uniformly bright elliptical disc (semi-axes a, b px, major axis at angle_deg), blurred by a
// Gaussian of sigma blur_px before the pixels integrate it (rendered on a 16x finer grid), peak
// `amplitude` electrons over `background` electrons.
cv::Mat1d RenderDisc(double cx, double cy, double a, double b, double angle_deg, double blur_px,
                     double amplitude, double background) {
  cv::Mat1f fine(kSide * kSuper, kSide * kSuper, 0.0f);
  const double c = std::cos(angle_deg * kPi / 180.0), s = std::sin(angle_deg * kPi / 180.0);
  for (int row = 0; row < fine.rows; ++row) {
    for (int col = 0; col < fine.cols; ++col) {
      const double x = (col + 0.5) / kSuper - 0.5 - cx, y = (row + 0.5) / kSuper - 0.5 - cy;
      const double u = c * x + s * y, v = -s * x + c * y;
      if ((u * u) / (a * a) + (v * v) / (b * b) <= 1.0) fine(row, col) = 1.0f;
    }
  }
  cv::GaussianBlur(fine, fine, cv::Size(0, 0), blur_px * kSuper);
  cv::Mat1f coarse;
  cv::resize(fine, coarse, cv::Size(kSide, kSide), 0, 0, cv::INTER_AREA);
  cv::Mat1d out;
  coarse.convertTo(out, CV_64F, amplitude, background);
  return out;
}

// Electrons -> a Mono12 frame (K 0.39 DN/e-, black 16 DN), with Poisson-like shot and 7 e- read
// noise when rng is set.
cv::Mat Frame(const cv::Mat1d& electrons, std::mt19937_64* rng) {
  cv::Mat out(electrons.size(), CV_16UC1);
  std::normal_distribution<double> unit(0.0, 1.0);
  for (int row = 0; row < out.rows; ++row) {
    for (int col = 0; col < out.cols; ++col) {
      double e = electrons(row, col);
      if (rng != nullptr) e += std::sqrt(e + 49.0) * unit(*rng);
      out.at<std::uint16_t>(row, col) =
          static_cast<std::uint16_t>(std::clamp(std::round(0.39 * e + 16.0), 0.0, 4095.0));
    }
  }
  return out;
}

// Mean of x and its sample standard deviation (*sd).
double MeanSd(const std::vector<double>& x, double* sd) {
  double m = 0, s = 0;
  for (double v : x) m += v / x.size();
  for (double v : x) s += (v - m) * (v - m) / (x.size() - 1);
  *sd = std::sqrt(s);
  return m;
}

const double kBlurPx = 0.75;
const double kBlurVar = kBlurPx * kBlurPx + 1.0 / 12.0;  // pixel area included

// Noise-free, the fit returns the rendered disc: variances a^2/4 and b^2/4, its centre and angle.
TEST(BlobFit, RecoversTheDiscOfANoiseFreeBlob) {
  const double a = 5.5, b = 4.2;
  const cv::Mat frame = Frame(RenderDisc(47.3, 48.6, a, b, 25.0, kBlurPx, 5000.0, 10.0), nullptr);
  const Features f = ComputeFeatures(frame, 12, FeatureOptions());
  ASSERT_TRUE(f.Usable()) << f.BriefReport();
  const BlobFitResult fit = FitBlob(frame, 12, f, kBlurVar);
  ASSERT_TRUE(fit.ok);
  EXPECT_NEAR(fit.major_var_px2 / (a * a / 4.0), 1.0, 0.003);
  EXPECT_NEAR(fit.minor_var_px2 / (b * b / 4.0), 1.0, 0.003);
  EXPECT_NEAR(fit.center_px.x, 47.3, 0.01);
  EXPECT_NEAR(fit.center_px.y, 48.6, 0.01);
  EXPECT_NEAR(fit.angle_deg, 25.0, 0.3);
  EXPECT_NEAR(fit.blur_var_px2, kBlurVar, 1e-12);
}

// The one-pass cost's profile in the blur (ProfileBlobBlur): from a blur 4% under or 4% over, the
// step lands on one minimum of the cost (noise free; 0.36% under the rendered blur: this
// renderer's Gaussian on its fine grid against the model's), and the slope is the refitted
// size's. Its standard error against the scatter: tests/estimator/refocus.
TEST(BlobFit, TheBlursProfileStepsToTheRenderedBlur) {
  const double a = 5.5, b = 4.2;
  const cv::Mat frame = Frame(RenderDisc(47.3, 48.6, a, b, 25.0, kBlurPx, 4000.0, 10.0), nullptr);
  const Features f = ComputeFeatures(frame, 12, FeatureOptions());
  ASSERT_TRUE(f.Usable()) << f.BriefReport();
  std::vector<double> minimum;
  for (const double given : {0.96 * kBlurVar, 1.04 * kBlurVar}) {
    const BlobBlurProfile p = ProfileBlobBlur(frame, 12, f, given, {});
    ASSERT_TRUE(p.ok);
    minimum.push_back(given + p.step_px2);
    EXPECT_NEAR(minimum.back(), kBlurVar, 0.004) << "given " << given;
    EXPECT_GT(std::abs(p.step_px2), 0.02) << "given " << given;
    const BlobFitResult at = FitBlobPasses(frame, 12, f, given, {}, 1);
    const BlobFitResult above = FitBlobPasses(frame, 12, f, given + 0.02, {}, 1);
    ASSERT_TRUE(at.ok && above.ok);
    EXPECT_NEAR(p.major_slope, (above.raw_major_var_px2 - at.raw_major_var_px2) / 0.02, 0.02);
  }
  EXPECT_NEAR(minimum[0], minimum[1], 3e-4);
}

// On noisy frames, the fit's size scatters less than the second moments' (they weight the noise
// of the wings by r^2), and its mean stays on the truth.
TEST(BlobFit, ScattersLessThanTheSecondMoments) {
  const double a = 5.5, b = 4.8;
  const cv::Mat1d electrons = RenderDisc(48.2, 47.7, a, b, -40.0, kBlurPx, 5000.0, 10.0);
  std::mt19937_64 rng(3);
  std::vector<double> fit_var, moment_var;
  for (int n = 0; n < 40; ++n) {
    const cv::Mat frame = Frame(electrons, &rng);
    const Features f = ComputeFeatures(frame, 12, FeatureOptions());
    ASSERT_TRUE(f.Usable());
    const BlobFitResult fit = FitBlob(frame, 12, f, kBlurVar);
    ASSERT_TRUE(fit.ok);
    fit_var.push_back(fit.major_var_px2);
    moment_var.push_back(f.moment_major_var_px2 - kBlurVar);
  }
  const auto mean_sd = [](const std::vector<double>& x, double* sd) {
    double m = 0, s = 0;
    for (double v : x) m += v / x.size();
    for (double v : x) s += (v - m) * (v - m) / (x.size() - 1);
    *sd = std::sqrt(s);
    return m;
  };
  double sd_fit = 0, sd_moments = 0;
  const double mean_fit = mean_sd(fit_var, &sd_fit);
  mean_sd(moment_var, &sd_moments);
  EXPECT_LT(sd_fit, 0.92 * sd_moments) << "fit " << sd_fit << " moments " << sd_moments;
  EXPECT_NEAR(mean_fit / (a * a / 4.0), 1.0, 0.004);
}

// The sizes' standard errors are the frame's own noise: over 60 noisy frames of a disc, round and
// elliptical, at a measurement frame's signal and at a reference frame's (a quarter of it), the
// trace size and the major-axis variance scatter as their reported errors say (sd / rms se within
// 0.75..1.25; the sampling of 60 sds is +-9%; measured over 200 frames: trace 1.01-1.06, major
// 0.80-1.03 with the round-blob rule's slope, the rule's smooth step taken linearly). Noise free
// the trace size is 1 / (2 tr P) = a^2 b^2 / (2 (a^2 + b^2)).
TEST(BlobFit, TheSizesErrorsAreTheirScatter) {
  const double a = 5.5;
  std::mt19937_64 rng(11);
  for (const double b : {5.5, 4.6}) {
    const double truth = a * a * b * b / (2.0 * (a * a + b * b));
    const cv::Mat exact = Frame(RenderDisc(47.6, 48.3, a, b, 35.0, kBlurPx, 4000.0, 10.0), nullptr);
    const BlobFitResult noise_free = FitBlob(exact, 12, ComputeFeatures(exact, 12, {}), kBlurVar);
    ASSERT_TRUE(noise_free.ok);
    EXPECT_NEAR(noise_free.trace_var_px2 / truth, 1.0, 0.003);
    for (const double amplitude : {4000.0, 1000.0}) {
      const cv::Mat1d electrons = RenderDisc(47.6, 48.3, a, b, 35.0, kBlurPx, amplitude, 10.0);
      std::vector<double> trace, major;
      double trace_se2 = 0.0, major_se2 = 0.0;
      for (int n = 0; n < 60; ++n) {
        const cv::Mat frame = Frame(electrons, &rng);
        const BlobFitResult fit = FitBlob(frame, 12, ComputeFeatures(frame, 12, {}), kBlurVar);
        ASSERT_TRUE(fit.ok);
        ASSERT_GT(fit.trace_var_se_px2, 0.0);
        ASSERT_GT(fit.major_var_se_px2, 0.0);
        trace.push_back(fit.trace_var_px2);
        major.push_back(fit.major_var_px2);
        trace_se2 += fit.trace_var_se_px2 * fit.trace_var_se_px2 / 60.0;
        major_se2 += fit.major_var_se_px2 * fit.major_var_se_px2 / 60.0;
      }
      double trace_sd = 0.0, major_sd = 0.0;
      MeanSd(trace, &trace_sd);
      MeanSd(major, &major_sd);
      const double trace_ratio = trace_sd / std::sqrt(trace_se2);
      const double major_ratio = major_sd / std::sqrt(major_se2);
      std::cout << "b " << b << " px, amplitude " << amplitude << " e-: sd / se trace "
                << trace_ratio << ", major " << major_ratio << "\n";
      EXPECT_GT(trace_ratio, 0.75);
      EXPECT_LT(trace_ratio, 1.25);
      EXPECT_GT(major_ratio, 0.75);
      EXPECT_LT(major_ratio, 1.25);
    }
  }
}

// On a round blob the larger eigenvalue of the fitted disc is the larger of two noisy axes: biased
// up (+0.2% here) and scattered by the anisotropy's noise. The size used for distance
// (major_var_px2: the continuous round-blob rule takes a blob round within its noise for a
// circle) scatters less than the raw larger eigenvalue (measured 0.95x over 150 frames) and is
// unbiased to the fit's own mean size (-0.057% on this 5 px disc at 0.75 px of blur: the edge
// model's third order, which the old rule's rare false ellipses offset by chance); a clearly
// elliptical disc keeps its axes.
TEST(BlobFit, ARoundBlobsSizeIsTheMeanOfItsAxesNotTheLargerOne) {
  const double a = 5.0;
  const int kFrames = 150;
  const cv::Mat1d electrons = RenderDisc(47.6, 48.3, a, a, 0.0, kBlurPx, 3000.0, 10.0);
  std::mt19937_64 rng(5);
  std::vector<double> used, raw;
  for (int n = 0; n < kFrames; ++n) {
    const cv::Mat frame = Frame(electrons, &rng);
    const Features f = ComputeFeatures(frame, 12, FeatureOptions());
    ASSERT_TRUE(f.Usable());
    const BlobFitResult fit = FitBlob(frame, 12, f, kBlurVar);
    ASSERT_TRUE(fit.ok);
    ASSERT_GT(fit.anisotropy_noise_var, 0.0);
    used.push_back(fit.major_var_px2 / (a * a / 4.0) - 1.0);
    raw.push_back(fit.raw_major_var_px2 / (a * a / 4.0) - 1.0);
  }
  double sd_used = 0, sd_raw = 0;
  const double bias_used = MeanSd(used, &sd_used), bias_raw = MeanSd(raw, &sd_raw);
  EXPECT_LT(sd_used, 0.97 * sd_raw) << "used " << sd_used << " raw " << sd_raw;
  EXPECT_GT(bias_raw, 5.0 * sd_raw / std::sqrt(kFrames)) << "the raw larger axis is biased up";
  EXPECT_LT(std::abs(bias_used), 0.35 * bias_raw) << "used " << bias_used << " raw " << bias_raw;
  EXPECT_LT(std::abs(bias_used), 6e-4);  // the fit's own: 0.06% of the size variance

  const cv::Mat1d ellipse = RenderDisc(47.6, 48.3, 5.5, 4.2, 30.0, kBlurPx, 3000.0, 10.0);
  const cv::Mat elliptic = Frame(ellipse, &rng);
  const Features f = ComputeFeatures(elliptic, 12, FeatureOptions());
  const BlobFitResult fit = FitBlob(elliptic, 12, f, kBlurVar);
  ASSERT_TRUE(fit.ok);
  EXPECT_NEAR(fit.major_var_px2 / fit.raw_major_var_px2, 1.0, 1e-3);
  EXPECT_NEAR(fit.minor_var_px2 / fit.raw_minor_var_px2, 1.0, 1e-3);
}

// The optics' PSF (sd 1.05 px along 30 deg, 0.7 across: an astigmatic lens) on a face-on disc of
// the independent renderer, noise free. Fitted with the round PSF of the same mean variance, the
// disc reads elliptical: its axes differ by 0.16-0.22 px (a tilt of 7-17 deg; the PSF's
// anisotropy is constant in pixels, so the false tilt falls with the disc's size). With the PSF's
// anisotropy in the edge model (each edge point spread by the PSF's variance along its normal and
// moved in by that along its tangent) they agree within 0.01 px (measured 0.003 px at 5 px, 0.001
// at 8), the size within 0.25%.
TEST(BlobFit, AnEllipticalPsfIsNotReadAsTilt) {
  const double l1 = 1.05 * 1.05, l2 = 0.7 * 0.7, turn = 60.0 * kPi / 180.0;  // 2 x 30 deg
  PsfAnisotropy psf;
  psf.c_px2 = 0.5 * (l1 - l2) * std::cos(turn);
  psf.s_px2 = 0.5 * (l1 - l2) * std::sin(turn);
  const double round_var = 0.5 * (l1 + l2);
  const double blur_var = round_var + 1.0 / 12.0;
  for (const double radius : {5.0, 8.0, 11.0}) {
    testing::DiscBlob blob;
    blob.cx = 31.3;
    blob.cy = 32.6;
    blob.a = blob.b = radius;
    blob.optics_sigma_px = std::sqrt(round_var);
    blob.psf_aniso_c_px2 = psf.c_px2;
    blob.psf_aniso_s_px2 = psf.s_px2;
    const cv::Mat frame =
        testing::DiscFrame16(testing::RenderDiscSpectrum(blob, 64), 50000.0, 1000.0);
    FeatureOptions options;
    options.window_side_px = 56;
    const Features f = ComputeFeatures(frame, 16, options);
    ASSERT_TRUE(f.Usable());
    Features without_psf = f;
    const BlobFitResult blind = FitBlob(frame, 16, without_psf, blur_var);
    Features moments = f;
    RemovePsfAnisotropy(psf.c_px2, psf.s_px2, &moments);
    const BlobFitResult fit = FitBlob(frame, 16, moments, blur_var, {}, psf);
    ASSERT_TRUE(blind.ok && fit.ok);
    const double blind_axes_px =
        2.0 * (std::sqrt(blind.raw_major_var_px2) - std::sqrt(blind.raw_minor_var_px2));
    const double axes_px = 2.0 * (std::sqrt(fit.raw_major_var_px2) - std::sqrt(fit.raw_minor_var_px2));
    EXPECT_GT(blind_axes_px, 0.12) << "radius " << radius;
    EXPECT_LT(axes_px, 0.01) << "radius " << radius << " (blind " << blind_axes_px << ")";
    const double size = 0.5 * (fit.raw_major_var_px2 + fit.raw_minor_var_px2);
    EXPECT_NEAR(size / (radius * radius / 4.0), 1.0, 2.5e-3) << "radius " << radius;
  }
}


// The blob fit's size over the edge's sub-pixel phase, noise free, on the independent
// renderer of tests/estimator/disc_spectrum.h (exact in the Fourier domain: the disc, the optical
// Gaussian before the pixels, their squares, the crosstalk after them): the disc's radius swept
// over 5..6 px in 0.05 px steps (the virtual rig's far end) and over 10..11 px, the fit given the
// blur and its split (the crosstalk's variance on the grid and its kernel: a sampled Gaussian, or a
// lattice random walk). For every mix of optics (0.3-1.0 px) and crosstalk (0-1.0 px) the
// relative distance error stays within 0.05% peak to peak (the fit
// the earlier fit, one Gaussian before the sampling, missed by 0.06-0.33%).
struct BlurMix {
  double optics_px, crosstalk_px;
  bool lattice = false;  // the crosstalk a lattice random walk, not a sampled Gaussian
};

double SizePeakToPeak(const BlurMix& mix, double first_radius_px, double* worst_bias) {
  const double crosstalk_var = mix.lattice ? mix.crosstalk_px * mix.crosstalk_px
                                           : testing::CrosstalkVariance(mix.crosstalk_px);
  const double blur_var = mix.optics_px * mix.optics_px + 1.0 / 12.0 + crosstalk_var;
  std::vector<double> error;
  for (int k = 0; k <= 20; ++k) {
    testing::DiscBlob blob;
    blob.cx = blob.cy = 23.5;  // on a pixel corner, as the rig's optical axis
    blob.a = blob.b = first_radius_px + 0.05 * k;
    blob.optics_sigma_px = mix.optics_px;
    blob.crosstalk_sigma_px = mix.crosstalk_px;
    blob.crosstalk_lattice = mix.lattice;
    const cv::Mat frame =
        testing::DiscFrame16(testing::RenderDiscSpectrum(blob, 48), 50000.0, 1000.0);
    FeatureOptions options;
    options.window_side_px = 40;
    const Features f = ComputeFeatures(frame, 16, options);
    if (!f.Usable()) return 1.0;
    const BlobFitResult fit =
        FitBlob(frame, 16, f, blur_var, {crosstalk_var, mix.lattice ? 1.0 : 0.0});
    if (!fit.ok) return 1.0;
    const double var = 0.5 * (fit.major_var_px2 + fit.minor_var_px2);
    error.push_back(-0.5 * (var / (blob.a * blob.a / 4.0) - 1.0));  // d ~ 1 / size
  }
  *worst_bias = std::max(std::fabs(*std::min_element(error.begin(), error.end())),
                         std::fabs(*std::max_element(error.begin(), error.end())));
  return testing::PeakToPeak(error);
}

TEST(BlobFit, SizeDoesNotDependOnTheEdgesPhaseWhateverTheBlurMix) {
  for (const BlurMix mix : {BlurMix{0.7, 0.0}, BlurMix{0.3, 0.0}, BlurMix{0.3, 0.8},
                            BlurMix{0.5, 0.6}, BlurMix{0.7, 0.6}, BlurMix{1.0, 1.0},
                            BlurMix{0.3, 0.4}, BlurMix{0.3, 0.8, true}}) {
    for (const double radius : {5.0, 10.0}) {
      double bias = 0.0;
      const double p2p = SizePeakToPeak(mix, radius, &bias);
      EXPECT_LT(p2p, 5e-4) << "optics " << mix.optics_px << " px, crosstalk " << mix.crosstalk_px
                           << " px, radius " << radius << " px";
      // The size's own bias, phase aside: within 0.05% up to 0.7 px of optics; the first-order
      // edge model's third-order error shows at 1 px of optics on a 5 px disc (0.06%).
      EXPECT_LT(bias, mix.optics_px <= 0.7 ? 5e-4 : 7.5e-4)
          << "optics " << mix.optics_px << " px, crosstalk "
                            << mix.crosstalk_px << " px, radius " << radius << " px";
    }
  }
}

// A calibration frame of a disc of `radius` px under `mix`, by the independent renderer, with its
// features (the blur is the caller's).
CrosstalkFrame DiscCalibrationFrame(const BlurMix& mix, double radius) {
  testing::DiscBlob blob;
  blob.cx = 23.3;
  blob.cy = 23.6;
  blob.a = blob.b = radius;
  blob.optics_sigma_px = mix.optics_px;
  blob.crosstalk_sigma_px = mix.crosstalk_px;
  blob.crosstalk_lattice = mix.lattice;
  CrosstalkFrame frame = testing::SpectrumFrame16(blob);
  return frame;
}

// The split of the blur from the frames alone (FitBlurSplit): discs of 5-10 px rendered by the
// independent renderer (crosstalk a sampled Gaussian or a lattice random walk), each given its
// total blur; the crosstalk's variance and its kernel's shape come back where the
// optics are sharp enough to show it, and at 0.7 px of optics (where the two blurs shape the edge
// alike) the fit with the split found still holds the size (the phase sweep's bound).
TEST(BlobFit, CalibrationFramesTellTheCrosstalkFromTheOptics) {
  for (const BlurMix mix : {BlurMix{0.3, 0.8}, BlurMix{0.5, 0.6}, BlurMix{0.3, 0.0},
                            BlurMix{0.7, 0.6}, BlurMix{0.3, 0.8, true}, BlurMix{0.5, 0.6, true}}) {
    const double crosstalk_var = mix.lattice ? mix.crosstalk_px * mix.crosstalk_px
                                             : testing::CrosstalkVariance(mix.crosstalk_px);
    std::vector<CrosstalkFrame> frames;
    for (const double radius : {5.0, 6.3, 7.7, 10.1}) {
      frames.push_back(DiscCalibrationFrame(mix, radius));
      frames.back().blur_var_px2 = mix.optics_px * mix.optics_px + 1.0 / 12.0 + crosstalk_var;
    }
    const BlurSplit split = FitBlurSplit(frames);
    EXPECT_EQ(split.frames, 4);
    const std::string what = "optics " + std::to_string(mix.optics_px) + " px, crosstalk " +
                             std::to_string(mix.crosstalk_px) + " px" +
                             (mix.lattice ? " (lattice)" : "");
    if (mix.optics_px <= 0.5) {
      EXPECT_NEAR(split.crosstalk_var_px2, crosstalk_var, 0.03) << what;
      // The kernel's shape where there is crosstalk to see.
      if (mix.crosstalk_px > 0.0) {
        EXPECT_NEAR(split.crosstalk_lattice_share, mix.lattice ? 1.0 : 0.0, 0.25) << what;
      }
      continue;
    }
    for (const CrosstalkFrame& f : frames) {
      const BlobFitResult fit = FitBlob(f.image, 16, f.features, f.blur_var_px2,
                                        {split.crosstalk_var_px2, split.crosstalk_lattice_share});
      ASSERT_TRUE(fit.ok) << what;
      const double radius = 2.0 * std::sqrt(0.5 * (fit.major_var_px2 + fit.minor_var_px2));
      const double true_radius = 2.0 * std::sqrt(f.features.moment_major_var_px2 -
                                                  f.blur_var_px2);  // the moments' own, exact here
      EXPECT_NEAR(radius / true_radius, 1.0, 1e-3) << what;
    }
  }
}

// The cumulants give a sharp edge's blur a few 0.01 px^2 off, and the fit's axis ratio needs it
// to a few 0.001 (a 0.03 px^2 error swings theta by 0.1-0.3 deg with the edges' phases on the
// sharp rig): FitBlurSplit returns the blob fit's own blur as a line in 1000 / d beside the split.
// Frames of the sharp mix given a blur 0.02 + 0.03 (1000 / d) px^2 too large: the blur it fits
// is the true one within 0.005 px^2 at every frame, and the split within 0.03.
TEST(BlobFit, CalibrationFramesGiveTheFitsOwnBlur) {
  const BlurMix mix{0.3, 0.8, true};
  const double crosstalk_var = mix.crosstalk_px * mix.crosstalk_px;
  const double true_blur = mix.optics_px * mix.optics_px + 1.0 / 12.0 + crosstalk_var;
  std::vector<CrosstalkFrame> frames;
  for (const double radius : {5.0, 6.3, 7.7, 10.1}) {
    CrosstalkFrame frame = DiscCalibrationFrame(mix, radius);
    frame.d_mm = 1500.0 * 10.1 / radius;
    frame.blur_var_px2 = true_blur + 0.02 + 0.03 * 1000.0 / frame.d_mm;
    frames.push_back(frame);
  }
  const BlurSplit split = FitBlurSplit(frames);
  EXPECT_NEAR(split.crosstalk_var_px2, crosstalk_var, 0.03);
  for (const CrosstalkFrame& f : frames) {
    const double fitted = f.blur_var_px2 + split.OffsetPx2(1000.0 / f.d_mm);
    EXPECT_NEAR(fitted, true_blur, 0.005) << "at " << f.d_mm << " mm";
  }
}

// Without a calibrated geometric model there is no blur to fit with: the features stay as they are.
TEST(BlobFit, RefineNeedsACalibratedBlur) {
  const cv::Mat frame = Frame(RenderDisc(48, 48, 5, 4, 0, kBlurPx, 5000, 10), nullptr);
  Features f = ComputeFeatures(frame, 12, FeatureOptions());
  const double before = f.moment_major_var_px2;
  EXPECT_FALSE(RefineWithBlobFit(frame, 12, CalibrationModel(), &f));
  EXPECT_EQ(f.moment_major_var_px2, before);
  EXPECT_FALSE(FitBlob(frame, 12, f, 0.05).ok);  // a blur below the pixel's own area
}

}  // namespace
}  // namespace irdist
