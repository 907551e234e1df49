#include "estimator/psf_anisotropy.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "base/pi.h"
#include "tests/estimator/disc_spectrum.h"

namespace irdist {
namespace {

// A 16-bit frame of the rendered blob with shot and read noise (50000 e- peak over 1000).
cv::Mat NoisyFrame(const cv::Mat1d& value, std::mt19937_64* rng) {
  std::normal_distribution<double> unit(0.0, 1.0);
  cv::Mat out(value.size(), CV_16UC1);
  for (int y = 0; y < value.rows; ++y) {
    for (int x = 0; x < value.cols; ++x) {
      const double e = 1000.0 + 50000.0 * value(y, x);
      out.at<std::uint16_t>(y, x) =
          static_cast<std::uint16_t>(std::clamp(std::round(e + std::sqrt(e) * unit(*rng)), 0.0,
                                                65535.0));
    }
  }
  return out;
}

// 24 noisy face-on discs of 5-11 px radius at scattered centres through a PSF of round sd
// `sigma_px` and anisotropy (c, s) px^2: their features.
std::vector<Features> FaceOnFrames(double sigma_px, double c, double s, std::mt19937_64* rng) {
  std::uniform_real_distribution<double> phase(0.0, 1.0);
  std::vector<Features> frames;
  for (int n = 0; n < 24; ++n) {
    testing::DiscBlob blob;
    blob.cx = 31.0 + phase(*rng);
    blob.cy = 31.0 + phase(*rng);
    blob.a = blob.b = 5.0 + 0.25 * n;
    blob.optics_sigma_px = sigma_px;
    blob.psf_aniso_c_px2 = c;
    blob.psf_aniso_s_px2 = s;
    FeatureOptions options;
    options.window_side_px = 56;
    frames.push_back(
        ComputeFeatures(NoisyFrame(testing::RenderDiscSpectrum(blob, 64), rng), 16, options));
  }
  return frames;
}

// Face-on discs of 5-11 px radius at scattered centres through an astigmatic lens (sd 1.05 px
// along 30 deg, 0.7 across): the PSF's anisotropy ((Sxx - Syy) / 2, Sxy) = (0.153, 0.265) px^2
// comes out of their moments within 3 standard errors and 0.02 px^2, the same at every size.
TEST(PsfAnisotropy, FaceOnFramesGiveThePsfsAnisotropy) {
  const double l1 = 1.05 * 1.05, l2 = 0.49, turn = 60.0 * kPi / 180.0;
  const double c = 0.5 * (l1 - l2) * std::cos(turn), s = 0.5 * (l1 - l2) * std::sin(turn);
  std::mt19937_64 rng(3);
  std::vector<Features> frames = FaceOnFrames(std::sqrt(0.5 * (l1 + l2)), c, s, &rng);
  const PsfAnisotropy psf = FitPsfAnisotropy(frames);
  ASSERT_GE(psf.frames, 20);
  EXPECT_NEAR(psf.c_px2, c, std::max(3.0 * psf.c_se_px2, 0.02));
  EXPECT_NEAR(psf.s_px2, s, std::max(3.0 * psf.s_se_px2, 0.02));
  EXPECT_LT(psf.c_se_px2, 0.02);
  EXPECT_TRUE(psf.Significant());
  // A round PSF: the anisotropy stays within its noise, and is not kept.
  const std::vector<Features> round_frames = FaceOnFrames(0.9, 0.0, 0.0, &rng);
  const PsfAnisotropy round = FitPsfAnisotropy(round_frames);
  EXPECT_GE(round.frames, 20);
  EXPECT_FALSE(round.Significant()) << round.c_px2 << " +- " << round.c_se_px2 << ", "
                                    << round.s_px2 << " +- " << round.s_se_px2;
  // Too few frames: nothing measured.
  frames.resize(kMinPsfAnisotropyFrames - 1);
  EXPECT_EQ(FitPsfAnisotropy(frames).frames, 0);
}

// A calibration keeps the anisotropy only where it stands out of its noise and a lens can have it:
// below 0.9 of the optics' least blur (a PSF's covariance is positive along every axis); a larger
// one is a cut or dirty disc's, and the PSF is taken as round.
TEST(PsfAnisotropy, ACalibrationKeepsOnlyWhatALensCanHave) {
  PsfAnisotropy psf;
  psf.c_px2 = -0.0515;
  psf.s_px2 = 0.003;
  psf.c_se_px2 = psf.s_se_px2 = 0.003;
  psf.frames = 40;
  ASSERT_TRUE(psf.Significant());
  const PsfAnisotropy kept = KeptPsfAnisotropy(psf, 0.4);  // an astigmatic lens's 10%
  EXPECT_EQ(kept.c_px2, psf.c_px2);
  EXPECT_EQ(kept.s_px2, psf.s_px2);
  EXPECT_EQ(kept.frames, 40);
  const double length = std::hypot(psf.c_px2, psf.s_px2);
  EXPECT_TRUE(PsfAnisotropyPossible(psf, length / 0.9 * 1.001));
  EXPECT_FALSE(PsfAnisotropyPossible(psf, length / 0.9 * 0.999));
  const PsfAnisotropy cut = KeptPsfAnisotropy(psf, length / 0.9 * 0.999);  // the scene's
  EXPECT_EQ(cut.c_px2, 0.0);
  EXPECT_EQ(cut.s_px2, 0.0);
  psf.c_se_px2 = psf.s_se_px2 = 0.02;  // within its noise: (0.0515 / 0.02)^2 + ... < 13.8
  ASSERT_FALSE(psf.Significant());
  const PsfAnisotropy noise = KeptPsfAnisotropy(psf, 0.4);
  EXPECT_EQ(noise.c_px2, 0.0);
  EXPECT_EQ(noise.s_px2, 0.0);
}

// The moments less the anisotropy: a covariance diag(6.3, 6.0) turned by 30 deg less its own
// traceless part is round, of the same mean.
TEST(PsfAnisotropy, RemovingItLeavesTheRoundPart) {
  Features f;
  f.ellipse_moments.valid = true;
  f.ellipse_moments.angle_deg = 30.0;
  f.moment_major_var_px2 = 6.3;
  f.moment_minor_var_px2 = 6.0;
  const double turn = 60.0 * kPi / 180.0;
  RemovePsfAnisotropy(0.15 * std::cos(turn), 0.15 * std::sin(turn), &f);
  EXPECT_NEAR(f.moment_major_var_px2, 6.15, 1e-12);
  EXPECT_NEAR(f.moment_minor_var_px2, 6.15, 1e-12);
  // Half of it: the rest keeps the direction.
  f.ellipse_moments.angle_deg = 30.0;
  f.moment_major_var_px2 = 6.3;
  f.moment_minor_var_px2 = 6.0;
  RemovePsfAnisotropy(0.075 * std::cos(turn), 0.075 * std::sin(turn), &f);
  EXPECT_NEAR(f.moment_major_var_px2 - f.moment_minor_var_px2, 0.15, 1e-12);
  EXPECT_NEAR(f.ellipse_moments.angle_deg, 30.0, 1e-9);
}

// The round-blob rule is continuous: no step anywhere (the hard rule jumped from 0 to 3x the
// noise at 4x), ~0 for a round blob's typical noise, the noise-bias-free |a|^2 for a clearly
// elliptical blob, and never above it.
TEST(PsfAnisotropy, TheRoundBlobRuleHasNoStep) {
  const double noise = 2e-5;
  double last = DenoisedAnisotropy2(0.0, noise), largest_step = 0.0;
  EXPECT_NEAR(last, 0.0, 1e-12);
  for (double t = 0.001; t <= 30.0; t += 0.001) {
    const double value = DenoisedAnisotropy2(t * noise, noise);
    largest_step = std::max(largest_step, std::fabs(value - last));
    EXPECT_GE(value, last - 1e-18) << "monotone at t " << t;
    EXPECT_LE(value, std::max(0.0, t * noise - noise) + 1e-18);
    last = value;
  }
  EXPECT_LT(largest_step, 0.01 * noise);  // steps of 0.001 noise move it by < 0.01 noise
  EXPECT_LT(DenoisedAnisotropy2(1.0 * noise, noise), 1e-12);  // a round blob's mean noise
  // theta > 2 deg (|a|^2 > 0.19 noise, as 3x reads 4 deg) only beyond t = 4.5: 1% of frames.
  EXPECT_LT(DenoisedAnisotropy2(4.5 * noise, noise), 0.19 * noise);
  // A 5 deg blob at 2 m on the virtual rig (t ~ 7.5) keeps 95% of its noise-free |a|^2.
  EXPECT_GT(DenoisedAnisotropy2(7.5 * noise, noise), 0.95 * 6.5 * noise);
  EXPECT_NEAR(DenoisedAnisotropy2(30.0 * noise, noise), 29.0 * noise, 1e-6 * noise);
  // Without a noise figure the anisotropy is kept as it is.
  EXPECT_EQ(DenoisedAnisotropy2(3e-5, std::nan("")), 3e-5);
}

}  // namespace
}  // namespace irdist
