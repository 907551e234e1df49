#include "estimator/refocus.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "estimator/blob_fit.h"
#include "estimator/blur_model.h"

namespace irdist {

namespace {

// Newton's method on the blur takes its last step when that step is below this share of the blur:
// the cost is then close to a parabola over the step (one step off by ~0.01-0.03 of the blur's
// standard error on the disc renderer of tests/estimator/refocus; the usual case, one profile).
constexpr double kLastStepShare = 0.02;
constexpr int kMaxNewtonSteps = 12;
// No step moves the blur by more than this share of it (the cost is far from a parabola a focus
// change away; the gradient's sign is right, its Newton step may overshoot).
constexpr double kMaxStepShare = 0.25;

}  // namespace

bool NewtonOnBlobBlur(const cv::Mat& image, int bit_depth, const Features& start,
                      const Crosstalk& crosstalk, double low, double high, double* blur,
                      BlobBlurProfile* at) {
  for (int k = 0; k < kMaxNewtonSteps; ++k) {
    *at = ProfileBlobBlur(image, bit_depth, start, *blur, crosstalk);
    if (!at->ok) return false;
    if (std::abs(at->step_px2) < kLastStepShare * *blur) {
      *blur += at->step_px2;
      return *blur > low && *blur < high;
    }
    const double reach = kMaxStepShare * *blur;
    const double next = std::clamp(*blur + std::clamp(at->step_px2, -reach, reach), low, high);
    if (next == *blur) return false;  // held on the search's edge
    *blur = next;
  }
  return false;
}

bool MeasureOwnBlur(const cv::Mat& image, int bit_depth, const CalibrationModel& model,
                    const Features& start, Features* out) {
  const double calibrated = out->size_blur_var_px2;
  if (!out->Usable() || !start.Usable() || !(calibrated > kPixelAreaVarPx2)) return false;
  const BlurCalibration& b = model.blur_calibration;
  const Crosstalk crosstalk = CrosstalkOf(b);
  // Past the crosstalk's kink too (blob_fit.h RoomFor): a search held there would read a sensor
  // whose blur is all after the pixels blurrier than calibrated, on noise alone.
  const double low = std::max(kOwnBlurLowFactor * calibrated, kLeastBlurVarPx2 + 1e-3);
  const double high = kOwnBlurHighFactor * calibrated;
  if (!(high > low)) return false;
  double own = calibrated;
  BlobBlurProfile p;
  if (!NewtonOnBlobBlur(image, bit_depth, start, crosstalk, low, high, &own, &p)) return false;
  out->own_blur_var_px2 = own;
  out->own_blur_se_px2 = p.se_px2;
  out->own_major_slope = p.major_slope;
  out->own_minor_slope = p.minor_slope;
  const double step = own - calibrated;
  if (std::abs(step) <= 0.05 * calibrated) {
    // Near the calibrated blur (the usual case: one profile): the refined disc moved along the
    // slopes, as AtBlur moves it.
    out->own_major_var_px2 = out->moment_major_var_px2 - calibrated + p.major_slope * step;
    out->own_minor_var_px2 = out->moment_minor_var_px2 - calibrated + p.minor_slope * step;
    return true;
  }
  // A focus change: the disc fitted at its own blur.
  const BlobFitResult fit = FitBlob(image, bit_depth, start, own, crosstalk);
  if (!fit.ok) return false;
  out->own_major_var_px2 = fit.major_var_px2;
  out->own_minor_var_px2 = fit.minor_var_px2;
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
