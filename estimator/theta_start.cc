#include "estimator/theta_start.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "base/check.h"
#include "base/pi.h"
#include "estimator/disc_fit.h"

namespace irdist {
namespace {

constexpr double kRad = kPi / 180.0;

// theta (deg) from moment variances with the calibrated blur removed, through the calibrated
// correction when the model has one and the options ask for it; NaN when the blob is not larger
// than the blur.
// `size_blur_var_px2`: the blur inside the variances where it is known (the blob fit's, which
// added it: then the ratio is the fitted disc's own), else NaN: the geometric model's b(u), whose
// fit also takes up the size model's misfit (0.045 px^2 above the calibrated blur at 1.5 m on the
// sharp rig: theta +0.05 deg there).
double ThetaFromVariances(const CalibrationModel& model, double major_var_px2,
                          double minor_var_px2, const ThetaStartOptions& options,
                          double size_blur_var_px2 = std::numeric_limits<double>::quiet_NaN()) {
  if (options.correction && model.theta_correction.fitted()) {
    return model.theta_correction.ThetaDeg(major_var_px2, minor_var_px2, model.geometric);
  }
  const double d_geo_mm = model.geometric.DistanceMm(major_var_px2);
  const double beta = std::isfinite(size_blur_var_px2) ? size_blur_var_px2
                      : std::isfinite(d_geo_mm)        ? model.geometric.BlurVarPx2(d_geo_mm)
                                                       : model.geometric.beta_px2;
  return Theta0FromVariances(minor_var_px2 - beta, major_var_px2 - beta);
}

// theta0 of one frame under the chosen source.
double Theta0(const CalibrationModel& model, const Features& f,
              const ThetaStartOptions& options) {
  if (options.from_features || !model.geometric.fitted()) {
    return f.theta0_deg;
  }
  const double theta = ThetaFromVariances(model, f.moment_major_var_px2, f.moment_minor_var_px2,
                                          options, f.size_blur_var_px2);
  return std::isfinite(theta) ? theta : f.theta0_deg;
}

}  // namespace

// theta0 from the signal-weighted mean of the frames' moment matrices (kBracketMoments), with the
// calibrated blur removed; falls back to Theta0 of `fallback` when no frame has moments.
double Theta0Combined(const CalibrationModel& model, const Features* const* frames, int count,
                      const Features& fallback, const ThetaStartOptions& options) {
  std::string why;
  IRDIST_CHECK(options.IsValid(&why), "ThetaStartOptions: " + why);
  if (!options.bracket_moments || !model.geometric.fitted()) {
    return Theta0(model, fallback, options);
  }
  double xx = 0.0, yy = 0.0, xy = 0.0, weight = 0.0;
  for (int i = 0; i < count; ++i) {
    const Features& f = *frames[i];
    if (!f.blob_found || !f.ellipse_moments.valid) continue;
    const double signal = f.f00 - f.background * f.roi_area_px;  // normalised gray levels
    if (!(signal > 0.0)) continue;
    const double a = f.ellipse_moments.angle_deg * kRad;
    const double c = std::cos(a), s = std::sin(a);
    const double l1 = f.moment_major_var_px2, l2 = f.moment_minor_var_px2;
    xx += signal * (l1 * c * c + l2 * s * s);
    yy += signal * (l1 * s * s + l2 * c * c);
    xy += signal * (l1 - l2) * s * c;
    weight += signal;
  }
  if (!(weight > 0.0)) return Theta0(model, fallback, options);
  xx /= weight;
  yy /= weight;
  xy /= weight;
  const double root = std::sqrt(std::max(0.0, 0.25 * (xx - yy) * (xx - yy) + xy * xy));
  const double theta =
      ThetaFromVariances(model, 0.5 * (xx + yy) + root, 0.5 * (xx + yy) - root, options);
  return std::isfinite(theta) ? theta : Theta0(model, fallback, options);
}

}  // namespace irdist
