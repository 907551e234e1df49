#pragma once
// The blob fit's edge correction, learned from the calibration frames (`irdist fit`, the
// accuracy study): a lens's edge need not be the fit's family (a Gaussian or Gram-Charlier edge
// integrated over the pixel's square, estimator/blob_pixel_model.h). Where it is not, the fitted
// size follows the edge's sub-pixel phase (docs/estimator.md "An edge correction learned from the
// calibration's own residuals"). The calibration frames hold the lens's own edge at every phase:
// each frame's residuals, relative to its fitted brightness, at each pixel's offset from the
// fitted edge (EdgeOffsetPx), averaged over the frames, are what the model misses there. That
// profile becomes a table added to the model's pixel mean (PixelResponse::edge_correction), and a
// second pass refines it with the correction in place. Learned only for a lens beyond the
// family (its edge fitted at the family's end, kEdgeFamilyEndExcess) and kept only where the
// first pass's profile stands out of its noise (kEdgeCorrectionEvidenceSd): every other lens
// keeps none, and its model is the family's as it was.

#include <cmath>
#include <string>
#include <vector>

#include "estimator/blob_fit.h"
#include "estimator/blur_model.h"

namespace irdist {

// One pass's residuals at the correction's knots (blur_model.h kEdgeCorrectionKnots).
class EdgeResiduals {
 public:
  EdgeResiduals();
  // Fits `frame` with the blob fit's blur at its distance (BlurCalibration::FitBlurVarPx2; the
  // given blur plus the offset when the distance is unknown), the split, the PSF's anisotropy and
  // the correction `blur` holds, and adds each pixel's residual within the table's reach, over
  // the fitted brightness, at its nearest knot. false when the fit fails (nothing added).
  bool Add(const CrosstalkFrame& frame, const BlurCalibration& blur);
  // Each knot's 10%-trimmed mean of its residuals (a hot pixel or a reflection in a frame does
  // not move it), that mean's standard error and the residuals' count; all 0 for a knot with
  // fewer than kMinKnotSamples.
  struct Knot {
    double mean = 0.0, se = 0.0, count = 0.0;
  };
  std::vector<Knot> Knots() const;
  // The knots' means smoothed over three knots (weighted by their counts) and tapered to 0 over
  // the table's outer pixel.
  static std::vector<double> Profile(const std::vector<Knot>& knots);
  // sum (mean / se)^2 over the knots that have residuals, and their number.
  static double Chi2(const std::vector<Knot>& knots, int* counted);

 private:
  std::vector<std::vector<float>> samples_;
};

// A knot's least residuals for its mean to count.
constexpr int kMinKnotSamples = 20;
// The evidence a first pass's profile must give to be kept: chi^2 above its knots' count by this
// many of its sd (sqrt(2 knots)): a lens the fit describes reads about 0 sd.
constexpr double kEdgeCorrectionEvidenceSd = 5.0;
// The passes: the profile, then its refinement with the correction in place.
constexpr int kEdgeCorrectionPasses = 2;
// A lens whose edge the calibration fits at the Gram-Charlier family's end (blob_fit.h
// kMaxOpticsExcess, within Brent's tolerance): a peaked core with heavy tails that the family
// cannot follow further (an Airy pattern). Only such a lens is given a correction. Within the
// family the residuals stand out too (a defocus disc's: 330-920 sd), and a correction takes the
// size's phase from 0.045-0.049% to 0.020-0.034% on the phase sweep, but it moved a small tilted
// disc's theta by -0.013 to -0.018 deg (4.5-5 px, 30 deg; the defocus lens's recordings: theta
// over its bound 1.35 where 1.28 without), and neither a curvature term nor the blur's level
// refitted with it took that back (docs/estimator.md "An edge correction learned from the
// calibration's own residuals").
constexpr double kEdgeFamilyEndExcess = kMaxOpticsExcess - 0.05;

// What LearnEdgeCorrection found: whether the lens's edge lies beyond the fit's family (its
// excess kurtosis at the family's end), the first pass's evidence in sd of chi^2 over its knots,
// the frames it used and whether the correction was kept.
struct EdgeCorrectionFit {
  bool beyond_family = false;
  double evidence_sd = 0.0;
  int frames = 0;
  bool kept = false;
};
// What `fit` found, in a line for a calibration's log (irdist fit, the accuracy study).
std::string DescribeEdgeCorrection(const EdgeCorrectionFit& fit);

// blur->edge_correction learned from the calibration frames `for_frames(use)` calls use(const
// CrosstalkFrame&) on (it may load them one at a time), with blur's split and blob fit blur as
// they are (after SetSplit): cleared, and no frame visited, for a lens within the fit's family;
// cleared when the first pass's evidence falls short.
template <typename ForFrames>
EdgeCorrectionFit LearnEdgeCorrection(ForFrames for_frames, BlurCalibration* blur) {
  EdgeCorrectionFit fit;
  blur->edge_correction.clear();
  fit.beyond_family = blur->optics_excess >= kEdgeFamilyEndExcess;
  for (int pass = 0; fit.beyond_family && pass < kEdgeCorrectionPasses; ++pass) {
    EdgeResiduals residuals;
    int frames = 0;
    for_frames([&](const CrosstalkFrame& f) { frames += residuals.Add(f, *blur) ? 1 : 0; });
    const std::vector<EdgeResiduals::Knot> knot_means = residuals.Knots();
    if (pass == 0) {
      int knots = 0;
      const double chi2 = EdgeResiduals::Chi2(knot_means, &knots);
      fit.frames = frames;
      fit.evidence_sd = knots > 0 ? (chi2 - knots) / std::sqrt(2.0 * knots) : 0.0;
      if (!(fit.evidence_sd > kEdgeCorrectionEvidenceSd)) return fit;
      blur->edge_correction.assign(kEdgeCorrectionKnots, 0.0);
    }
    const std::vector<double> step = EdgeResiduals::Profile(knot_means);
    for (int k = 0; k < kEdgeCorrectionKnots; ++k) {  // whole 1e-6: the model file's digits
      blur->edge_correction[k] = std::round((blur->edge_correction[k] + step[k]) * 1e6) / 1e6;
    }
  }
  fit.kept = !blur->edge_correction.empty();
  return fit;
}

}  // namespace irdist
