#include "estimator/edge_correction.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>
#include <vector>

#include "base/pi.h"
#include "estimator/blob_pixel_model.h"

namespace irdist {
namespace {

// The share of a knot's residuals left out at each end of its trimmed mean.
constexpr double kTrimShare = 0.1;
// The fitted disc's reach past its semi-major axis that the residuals cover: the table's, plus a
// pixel's half diagonal.
constexpr double kReachPastTablePx = 1.0;

// The fitted disc (x, y relative to `origin`, P11, P12, P22) from the fit's centre, raw axes'
// variances (A^2 / 4, B^2 / 4) and the major axis's angle.
void DiscOf(const BlobFitResult& fit, cv::Point origin, double* v) {
  const double a = fit.angle_deg * kPi / 180.0, c = std::cos(a), s = std::sin(a);
  const double p_major = 0.25 / fit.raw_major_var_px2, p_minor = 0.25 / fit.raw_minor_var_px2;
  v[0] = fit.center_px.x - origin.x;
  v[1] = fit.center_px.y - origin.y;
  v[2] = p_major * c * c + p_minor * s * s;
  v[3] = (p_major - p_minor) * c * s;
  v[4] = p_major * s * s + p_minor * c * c;
}

// The blob fit's model of the pixels of `box` (relative to box.tl(), row by row) for the disc v:
// each pixel's mean on the box grown by the crosstalk's reach, then spread by its kernel.
std::vector<double> ModelOfBox(const double* v, cv::Size box, const blob_model::PixelResponse& r) {
  const int reach = r.reach, cols = box.width + 2 * reach, rows = box.height + 2 * reach;
  std::vector<double> grown(static_cast<size_t>(cols) * rows);
  double d[5];
  for (int row = 0; row < rows; ++row) {
    for (int col = 0; col < cols; ++col) {
      grown[static_cast<size_t>(row) * cols + col] =
          blob_model::SquareMean(v, col - reach, row - reach, r, d);
    }
  }
  if (reach == 0) return grown;
  std::vector<double> across, out(box.area());
  blob_model::Spread(grown.data(), rows, cols, r.kernel, &across, out.data());
  return out;
}

// The mean of `x` without its kTrimShare at each end, and that mean's standard error (Tukey and
// McLaughlin: the winsorized sd over (1 - 2 share) sqrt(n); the trimmed values' own sd would
// understate it by a fifth for normal noise).
void TrimmedMean(std::vector<float> x, double* mean, double* se) {
  std::sort(x.begin(), x.end());
  const size_t n = x.size(), cut = static_cast<size_t>(kTrimShare * static_cast<double>(n));
  double sum = 0.0;
  for (size_t i = cut; i < n - cut; ++i) sum += x[i];
  *mean = sum / static_cast<double>(n - 2 * cut);
  double winsorized = 0.0, sum2 = 0.0;
  for (size_t i = 0; i < n; ++i) {
    const double w = x[std::clamp(i, cut, n - cut - 1)];
    winsorized += w, sum2 += w * w;
  }
  winsorized /= static_cast<double>(n);
  const double var = std::max(sum2 / static_cast<double>(n) - winsorized * winsorized, 0.0);
  *se = std::sqrt(var / static_cast<double>(n)) * static_cast<double>(n) /
        static_cast<double>(n - 2 * cut);
}

}  // namespace

EdgeResiduals::EdgeResiduals() : samples_(kEdgeCorrectionKnots) {}

bool EdgeResiduals::Add(const CrosstalkFrame& frame, const BlurCalibration& blur) {
  const double blur_var =
      frame.d_mm > 0.0 ? blur.FitBlurVarPx2(frame.d_mm) : frame.blur_var_px2 + blur.fit_offset_px2;
  const Crosstalk crosstalk = RoomFor(CrosstalkOf(blur), blur_var);
  const PsfAnisotropy psf = PsfOf(blur);
  const BlobFitResult fit =
      FitBlob(frame.image, frame.bit_depth, frame.features, blur_var, crosstalk, psf);
  if (!fit.ok || !(fit.amplitude > 0.0) || !(fit.raw_minor_var_px2 > 0.0)) return false;
  const double half =
      2.0 * std::sqrt(fit.raw_major_var_px2) + kEdgeCorrectionHalfWidthPx + kReachPastTablePx;
  const cv::Rect box = cv::Rect(cvFloor(fit.center_px.x - half), cvFloor(fit.center_px.y - half),
                                cvCeil(2.0 * half) + 1, cvCeil(2.0 * half) + 1) &
                       cv::Rect(0, 0, frame.image.cols, frame.image.rows);
  if (box.empty()) return false;
  const blob_model::PixelResponse r = ResponseOf(blur_var, crosstalk, psf);
  double v[5];
  DiscOf(fit, box.tl(), v);
  const std::vector<double> model = ModelOfBox(v, box.size(), r);
  const double scale = 1.0 / ((1 << frame.bit_depth) - 1);
  for (int row = 0; row < box.height; ++row) {
    for (int col = 0; col < box.width; ++col) {
      const double t = blob_model::EdgeOffsetPx(v, col, row, r);
      const double u = (t + kEdgeCorrectionHalfWidthPx) / kEdgeCorrectionStepPx;
      if (!(u >= 0.0) || !(u <= kEdgeCorrectionKnots - 1)) continue;
      const double value = frame.image.at<std::uint16_t>(box.y + row, box.x + col) * scale;
      const double residual = (value - fit.background) / fit.amplitude -
                              model[static_cast<size_t>(row) * box.width + col];
      samples_[std::lround(u)].push_back(static_cast<float>(residual));
    }
  }
  return true;
}

std::vector<EdgeResiduals::Knot> EdgeResiduals::Knots() const {
  std::vector<Knot> out(kEdgeCorrectionKnots);
  for (int k = 0; k < kEdgeCorrectionKnots; ++k) {
    if (samples_[k].size() < static_cast<size_t>(kMinKnotSamples)) continue;
    TrimmedMean(samples_[k], &out[k].mean, &out[k].se);
    out[k].count = static_cast<double>(samples_[k].size());
  }
  return out;
}

std::vector<double> EdgeResiduals::Profile(const std::vector<Knot>& knots) {
  std::vector<double> out(kEdgeCorrectionKnots, 0.0);
  for (int k = 0; k < kEdgeCorrectionKnots; ++k) {
    double sum = 0.0, w = 0.0;
    for (int j = std::max(k - 1, 0); j <= std::min(k + 1, kEdgeCorrectionKnots - 1); ++j) {
      sum += knots[j].count * knots[j].mean, w += knots[j].count;
    }
    // Tapered as sin^2 over the outer pixel: 0 at the table's ends.
    const double from_end = kEdgeCorrectionHalfWidthPx -
                            std::fabs(k * kEdgeCorrectionStepPx - kEdgeCorrectionHalfWidthPx);
    const double taper = std::sin(0.5 * kPi * std::min(from_end, 1.0));
    out[k] = w > 0.0 ? taper * taper * sum / w : 0.0;
  }
  return out;
}

double EdgeResiduals::Chi2(const std::vector<Knot>& knots, int* counted) {
  double chi2 = 0.0;
  *counted = 0;
  for (const Knot& k : knots) {
    if (!(k.count > 0.0) || !(k.se > 0.0)) continue;
    chi2 += (k.mean / k.se) * (k.mean / k.se);
    ++*counted;
  }
  return chi2;
}

std::string DescribeEdgeCorrection(const EdgeCorrectionFit& fit) {
  if (!fit.beyond_family) return "none (the lens's edge lies within the fit's family)";
  std::ostringstream out;
  out << "the lens's edge lies beyond the fit's family (its excess kurtosis at the family's "
      << "end); the residuals at the fitted edges stand " << fit.evidence_sd
      << " sd out of their noise on " << fit.frames
      << " frames: " << (fit.kept ? "learned" : "none (within their noise)");
  return out.str();
}

}  // namespace irdist
