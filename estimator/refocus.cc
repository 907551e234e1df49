#include "estimator/refocus.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <boost/math/tools/minima.hpp>

#include "estimator/blob_fit.h"
#include "estimator/blur_model.h"

namespace irdist {

namespace {

// The step (px^2) of the slopes of the disc's variances in the blur.
constexpr double kSlopeStepPx2 = 0.05;

// FitBlobPasses's window around the blob (its half side) for a start's moment variance and a
// blur: 2 moment sd + 4 blur sd + 2 px.
double WindowHalf(double moment_var_px2, double blur_var_px2) {
  return 2.0 * std::sqrt(std::max(moment_var_px2, 0.0)) + 4.0 * std::sqrt(blur_var_px2) + 2.0;
}

// One frame's blob-fit cost against the blur variance, as FitBlurSplit minimises it (one pass,
// the read noise's weights), made a smooth function of the blur: FitBlobPasses sizes its window
// and the ring it measures the read noise on from the blur it is given, so the cost steps
// wherever a row of pixels enters or the ring's robust sd moves by a gray level. The start's
// moment variances move with the blur so that the window stays the one at the calibrated blur,
// and the cost is the residual sum of squares (chi^2 times the ring's read variance, computed as
// FitBlobPasses does) over the read variance at the calibrated blur.
class OwnBlurCost {
 public:
  OwnBlurCost(const cv::Mat& image, int bit_depth, const Features& start, double calibrated,
              const Crosstalk& xt)
      : image_(image), bit_depth_(bit_depth), start_(start), crosstalk_(xt),
        half_(WindowHalf(start.moment_major_var_px2, calibrated)) {
    reference_var_ = RingVariance(StartAt(calibrated), calibrated);
  }
  double operator()(double blur_var_px2) const { return Evaluate(blur_var_px2, nullptr); }
  // The cost, its value per pixel (*per_pixel) and the fit (*fit, when given); +inf when the fit
  // fails.
  double Evaluate(double blur_var_px2, double* per_pixel, BlobFitResult* fit_out = nullptr) const {
    const Features start = StartAt(blur_var_px2);
    const BlobFitResult fit =
        FitBlobPasses(image_, bit_depth_, start, blur_var_px2, crosstalk_, 1);
    if (fit_out != nullptr) *fit_out = fit;
    if (!fit.ok || !(reference_var_ > 0.0)) return std::numeric_limits<double>::infinity();
    const double scale = RingVariance(start, blur_var_px2) / reference_var_;
    if (per_pixel != nullptr) *per_pixel = fit.read_weighted_chi2 * scale;
    return fit.read_weighted_chi2 * fit.pixels * scale;
  }

 private:
  // The start with its moment variances shifted so that its window is the calibrated blur's.
  Features StartAt(double blur_var_px2) const {
    Features f = start_;
    const double root = 0.5 * (half_ - 4.0 * std::sqrt(blur_var_px2) - 2.0);
    const double shift = root * root - f.moment_major_var_px2;
    f.moment_major_var_px2 += shift;
    f.moment_minor_var_px2 += shift;
    return f;
  }
  // The read variance FitBlobPasses weights with: the robust sd of the window's pixels beyond the
  // blob's reach, at least the quantisation's.
  double RingVariance(const Features& f, double blur_var_px2) const {
    const double half = WindowHalf(f.moment_major_var_px2, blur_var_px2);
    const cv::Point2d c = f.ellipse_moments.center_px;
    const cv::Rect box = cv::Rect(cvRound(c.x - half), cvRound(c.y - half),
                                  cvRound(2 * half) + 1, cvRound(2 * half) + 1) &
                         cv::Rect(0, 0, image_.cols, image_.rows);
    const double reach = 2.0 * std::sqrt(f.moment_major_var_px2) +
                         3.0 * std::sqrt(blur_var_px2 - kPixelAreaVarPx2);
    const double scale = 1.0 / ((1 << bit_depth_) - 1);
    std::vector<double> ring;
    for (int row = box.y; row < box.br().y; ++row) {
      for (int col = box.x; col < box.br().x; ++col) {
        if (std::hypot(col - c.x, row - c.y) > reach) {
          ring.push_back(image_.at<std::uint16_t>(row, col) * scale);
        }
      }
    }
    const double sd = ring.size() < 16 ? 0.0 : RobustNoiseSd(&ring);
    return std::max(sd * sd, scale * scale / 12.0);
  }

  const cv::Mat& image_;
  int bit_depth_;
  const Features& start_;
  Crosstalk crosstalk_;
  double half_;
  double reference_var_ = 0.0;
};

// A parabola through the cost at five blurs: its vertex, the minimum's standard error (from its
// curvature, scaled by the cost per pixel; NaN when the cost is not convex there), whether the
// vertex lies inside the central three points, and the slopes of the disc's variances in the
// blur between the second and fourth (the first pass's raw sizes).
struct Parabola {
  double vertex = 0.0, se = std::numeric_limits<double>::quiet_NaN();
  bool inside = false;
  double major_slope = 0.0, minor_slope = 0.0;
};

// The parabola through five points 5% of the blur apart centred at `at` (moved up where the
// lowest would leave the search above `low`), fitted by least squares.
Parabola FitParabola(const OwnBlurCost& cost, double low, double at) {
  Parabola out;
  const double h = std::max(0.05 * at, 0.005);
  const double centre = std::max(at, low + 2.0 * h);
  double c[5], per_pixel = 0.0;
  BlobFitResult below, above;
  for (int j = -2; j <= 2; ++j) {
    const double b = centre + j * h;
    c[j + 2] = j == 0 ? cost.Evaluate(b, &per_pixel)
                      : cost.Evaluate(b, nullptr, j == -1 ? &below : j == 1 ? &above : nullptr);
  }
  double linear = 0.0, quadratic = 0.0;  // per step: sum j c_j / 10, sum (j^2 - 2) c_j / 14
  for (int j = -2; j <= 2; ++j) {
    linear += j * c[j + 2] / 10.0;
    quadratic += (j * j - 2) * c[j + 2] / 14.0;
  }
  out.vertex = centre;
  if (!(quadratic > 0.0) || !std::isfinite(quadratic) || !(per_pixel > 0.0)) return out;
  const double step = -linear / (2.0 * quadratic);
  out.inside = std::abs(step) < 1.0;
  out.vertex = centre + std::clamp(step, -2.0, 2.0) * h;
  out.se = std::sqrt(2.0 * per_pixel / (2.0 * quadratic / (h * h)));
  out.major_slope = (above.raw_major_var_px2 - below.raw_major_var_px2) / (2.0 * h);
  out.minor_slope = (above.raw_minor_var_px2 - below.raw_minor_var_px2) / (2.0 * h);
  return out;
}

// Near the calibrated blur (the parabola around it holds its own vertex: the usual case, five
// one-pass fits): the disc at the calibrated blur (the refined features) moved along the
// parabola's slopes. False when the vertex lies beyond (a focus change: the far search).
bool OwnBlurNearCalibrated(const OwnBlurCost& cost, double low, Features* out) {
  const double calibrated = out->size_blur_var_px2;
  const Parabola p = FitParabola(cost, low, calibrated);
  if (!p.inside || !std::isfinite(p.se)) return false;
  const double step = p.vertex - calibrated;
  out->own_blur_var_px2 = p.vertex;
  out->own_blur_se_px2 = p.se;
  out->own_major_slope = p.major_slope;
  out->own_minor_slope = p.minor_slope;
  out->own_major_var_px2 = out->moment_major_var_px2 - calibrated + p.major_slope * step;
  out->own_minor_var_px2 = out->moment_minor_var_px2 - calibrated + p.minor_slope * step;
  return true;
}

}  // namespace

bool MeasureOwnBlur(const cv::Mat& image, int bit_depth, const CalibrationModel& model,
                    const Features& start, Features* out) {
  const double calibrated = out->size_blur_var_px2;
  if (!out->Usable() || !start.Usable() || !(calibrated > kPixelAreaVarPx2)) return false;
  const BlurCalibration& b = model.blur_calibration;
  const Crosstalk crosstalk(b.crosstalk_var_px2, b.crosstalk_lattice_share);
  const OwnBlurCost cost(image, bit_depth, start, calibrated, crosstalk);
  const double floor = kPixelAreaVarPx2 + kMinOpticsVarPx2 + crosstalk.var_px2;
  const double low = std::max(kOwnBlurLowFactor * calibrated, floor + 1e-3);
  const double high = kOwnBlurHighFactor * calibrated;
  if (!(high > low)) return false;
  if (OwnBlurNearCalibrated(cost, low, out)) return true;
  // Far from it: Brent over the search, the parabola at its minimum, the disc fitted there.
  boost::uintmax_t iterations = 40;
  const double found = boost::math::tools::brent_find_minima(cost, low, high, 10, iterations).first;
  const double edge = 0.01 * (high - low);
  if (found < low + edge || found > high - edge) return false;
  const Parabola p = FitParabola(cost, low, found);
  const double own = p.vertex;
  const BlobFitResult at = FitBlob(image, bit_depth, start, own, crosstalk);
  const BlobFitResult above = FitBlob(image, bit_depth, start, own + kSlopeStepPx2, crosstalk);
  if (!std::isfinite(p.se) || !at.ok || !above.ok) return false;
  out->own_blur_var_px2 = own;
  out->own_blur_se_px2 = p.se;
  out->own_major_var_px2 = at.major_var_px2;
  out->own_minor_var_px2 = at.minor_var_px2;
  out->own_major_slope = (above.raw_major_var_px2 - at.raw_major_var_px2) / kSlopeStepPx2;
  out->own_minor_slope = (above.raw_minor_var_px2 - at.raw_minor_var_px2) / kSlopeStepPx2;
  return true;
}

BracketBlur FitBracketBlur(const std::vector<const Features*>& frames) {
  BracketBlur out;
  double sw = 0.0, swb = 0.0, swc = 0.0;
  std::vector<std::pair<double, double>> points;  // (own blur, weight)
  for (const Features* f : frames) {
    if (f == nullptr || !std::isfinite(f->own_blur_var_px2) || !(f->own_blur_se_px2 > 0.0) ||
        !std::isfinite(f->size_blur_var_px2)) {
      continue;
    }
    const double w = 1.0 / (f->own_blur_se_px2 * f->own_blur_se_px2);
    sw += w;
    swb += w * f->own_blur_var_px2;
    swc += w * f->size_blur_var_px2;
    points.emplace_back(f->own_blur_var_px2, w);
  }
  out.frames = static_cast<int>(points.size());
  if (out.frames == 0) return out;
  out.blur_var_px2 = swb / sw;
  out.calibrated_px2 = swc / sw;
  double chi2 = 0.0;
  for (const auto& [blur, w] : points) {
    chi2 += w * (blur - out.blur_var_px2) * (blur - out.blur_var_px2);
  }
  out.chi2_per_dof = out.frames > 1 ? chi2 / (out.frames - 1) : 0.0;
  out.se_px2 = std::sqrt(std::max(out.chi2_per_dof, 1.0) / sw);
  return out;
}

Features AtBlur(const Features& f, double blur_var_px2) {
  Features g = f;
  if (!std::isfinite(f.own_blur_var_px2) || !std::isfinite(f.size_blur_var_px2)) return g;
  const double step = blur_var_px2 - f.own_blur_var_px2;
  const double major = f.own_major_var_px2 + f.own_major_slope * step;
  const double minor = f.own_minor_var_px2 + f.own_minor_slope * step;
  g.moment_major_var_px2 = std::max(major, minor) + f.size_blur_var_px2;
  g.moment_minor_var_px2 = std::max(std::min(major, minor), 0.0) + f.size_blur_var_px2;
  return g;
}

}  // namespace irdist
