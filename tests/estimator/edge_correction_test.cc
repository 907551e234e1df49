// The blob fit's edge correction learned from calibration frames (estimator/edge_correction.h):
// none for a lens the fit's edge family describes, and for a lens outside it (an Airy PSF: its
// line spread falls as x^-2, which no Gram-Charlier edge follows) a table that makes the fit's
// pixels the lens's. The frames come from the test renderers (tests/estimator/disc_spectrum.h,
// pixel_responses.h), built from the optics' transfer functions, not from the fit's model.
#include "estimator/edge_correction.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "estimator/blob_fit.h"
#include "estimator/features.h"
#include "tests/estimator/disc_spectrum.h"
#include "tests/estimator/pixel_responses.h"

namespace irdist {
namespace {

constexpr int kSide = 44;

Features FeaturesOf(const cv::Mat& frame) {
  FeatureOptions options;
  options.window_side_px = 36;
  return ComputeFeatures(frame, 12, options);
}

// A disc's noise-free image (unit brightness) of radius `radius_px` centred at (cx, cy).
using Render = std::function<cv::Mat1d(double cx, double cy, double radius_px)>;

// `count` noisy 12-bit frames of discs of radius 4.5-9 px at random sub-pixel centres, each with
// the blob fit's blur `blur_var_px2` (the distance unknown).
std::vector<CrosstalkFrame> Frames(const Render& render, int count, double blur_var_px2,
                                   unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> phase(-0.5, 0.5), radius(4.5, 9.0);
  std::vector<CrosstalkFrame> out;
  for (int i = 0; i < count; ++i) {
    CrosstalkFrame f;
    const double cx = 0.5 * kSide + phase(rng), cy = 0.5 * kSide + phase(rng);
    f.image = testing::NoisyFrame12(render(cx, cy, radius(rng)), &rng);
    f.features = FeaturesOf(f.image);
    f.blur_var_px2 = blur_var_px2;
    if (f.features.Usable()) out.push_back(f);
  }
  return out;
}

// A blur calibration of a constant blur (the fit's, pixel area included) and an optics' edge.
BlurCalibration ConstantBlur(double blur_var_px2, double optics_excess) {
  BlurCalibration b;
  b.c0_px2 = blur_var_px2;
  b.noise_at_1m_px2 = 0.01;  // fitted()
  b.frames = 64;
  b.optics_excess = optics_excess;
  return b;
}

EdgeCorrectionFit Learn(const std::vector<CrosstalkFrame>& frames, BlurCalibration* blur) {
  return LearnEdgeCorrection(
      [&](const auto& use) {
        for (const CrosstalkFrame& f : frames) use(f);
      },
      blur);
}

// A round Gaussian lens (0.7 px before the pixels, their full squares): the fit's own family, so
// its residuals at the edge are noise (the evidence within kEdgeCorrectionEvidenceSd), and with
// its edge fitted inside the family (a Gaussian's excess kurtosis, 0) no correction is learned
// and no frame visited: the model is the family's.
TEST(EdgeCorrection, ALensTheFitsEdgeDescribesKeepsNone) {
  const Render gaussian = [](double cx, double cy, double radius_px) {
    testing::DiscBlob blob;
    blob.cx = cx, blob.cy = cy, blob.a = blob.b = radius_px;
    blob.optics_sigma_px = 0.7;
    return testing::RenderDiscSpectrum(blob, kSide);
  };
  const double blur = 0.49 + 1.0 / 12.0;
  BlurCalibration b = ConstantBlur(blur, 0.0);
  const std::vector<CrosstalkFrame> frames = Frames(gaussian, 64, blur, 3);
  EdgeResiduals residuals;
  for (const CrosstalkFrame& f : frames) EXPECT_TRUE(residuals.Add(f, b));
  int knots = 0;
  const double evidence_sd =
      (EdgeResiduals::Chi2(residuals.Knots(), &knots) - knots) / std::sqrt(2.0 * knots);
  std::printf("Gaussian lens: residuals %.1f sd out of their noise over %d knots\n", evidence_sd,
              knots);
  EXPECT_GT(knots, 80);
  EXPECT_LT(std::abs(evidence_sd), kEdgeCorrectionEvidenceSd);
  b.edge_correction.assign(kEdgeCorrectionKnots, 0.01);  // a stale table is cleared
  int visited = 0;
  const EdgeCorrectionFit fit = LearnEdgeCorrection(
      [&](const auto& use) {
        for (const CrosstalkFrame& f : frames) use(f), ++visited;
      },
      &b);
  EXPECT_FALSE(fit.beyond_family);
  EXPECT_FALSE(fit.kept);
  EXPECT_EQ(visited, 0);
  EXPECT_TRUE(b.edge_correction.empty());
}

// The calibration's log line (irdist fit's and the accuracy study's) says which case applied.
TEST(EdgeCorrection, TheLogSaysWhetherItWasLearnedAndWhy) {
  EdgeCorrectionFit fit;
  EXPECT_EQ(DescribeEdgeCorrection(fit), "none (the lens's edge lies within the fit's family)");
  fit.beyond_family = true, fit.evidence_sd = 2.5, fit.frames = 64;
  const std::string noise = DescribeEdgeCorrection(fit);
  EXPECT_NE(noise.find("stand 2.5 sd out of their noise on 64 frames: none"), std::string::npos)
      << noise;
  fit.evidence_sd = 7300.0, fit.kept = true;
  const std::string learned = DescribeEdgeCorrection(fit);
  EXPECT_NE(learned.find("7300 sd"), std::string::npos) << learned;
  EXPECT_EQ(learned.substr(learned.size() - 7), "learned") << learned;
}

// The fit's one-pass cost on a noise-free disc of the Airy PSF (read noise weights).
double AiryCost(const BlurCalibration& b, double cx, double cy, double radius_px) {
  const cv::Mat frame =
      testing::DiscFrame12(cx, cy, radius_px, testing::PixelResponseKind::kAiry, kSide);
  const BlobFitResult fit =
      FitBlobPasses(frame, 12, FeaturesOf(frame), b.c0_px2, CrosstalkOf(b), 1);
  EXPECT_TRUE(fit.ok);
  return fit.read_weighted_chi2;
}

// An Airy PSF (cut-off 0.7 cycles / px) with the Gram-Charlier edge at its end (g = 4, beyond the
// family) and the blur a calibration gives it: the residuals stand far out of their noise, the
// correction is kept, tapered to 0 at the table's ends, and noise-free discs the calibration
// never saw (other radii and centres) fit with a fraction of the cost they had without it.
TEST(EdgeCorrection, AnAiryLensEdgeIsLearnedAndItsDiscsFitAsTheyAre) {
  const Render airy = [](double cx, double cy, double radius_px) {
    testing::FlatDisc disc;
    disc.cx = cx, disc.cy = cy, disc.radius_px = radius_px;
    return testing::RenderResponse(disc, testing::PixelResponseKind::kAiry, kSide);
  };
  const double blur = 1.05;
  BlurCalibration b = ConstantBlur(blur, 4.0);
  const BlurCalibration plain = b;
  const EdgeCorrectionFit fit = Learn(Frames(airy, 64, blur, 5), &b);
  std::printf("Airy PSF: residuals %.0f sd out of their noise on %d frames\n", fit.evidence_sd,
              fit.frames);
  EXPECT_TRUE(fit.beyond_family);
  EXPECT_TRUE(fit.kept);
  EXPECT_EQ(fit.frames, 64);
  EXPECT_GT(fit.evidence_sd, 100.0);
  ASSERT_EQ(b.edge_correction.size(), static_cast<size_t>(kEdgeCorrectionKnots));
  EXPECT_EQ(b.edge_correction.front(), 0.0);
  EXPECT_EQ(b.edge_correction.back(), 0.0);
  for (const auto& [cx, cy, r] :
       {std::tuple{21.5, 21.5, 7.3}, {22.0, 22.0, 5.1}, {21.8, 22.3, 8.6}, {22.2, 21.6, 4.7}}) {
    const double before = AiryCost(plain, cx, cy, r), after = AiryCost(b, cx, cy, r);
    std::printf(
        "Airy disc R %.1f px at (%.1f, %.1f): the fit's cost %.1f, with the correction %.1f\n", r,
        cx, cy, before, after);
    EXPECT_LT(after, 0.25 * before) << "R " << r << ": " << before << " -> " << after;
  }
}

}  // namespace
}  // namespace irdist
