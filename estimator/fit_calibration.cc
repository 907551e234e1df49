// The whole calibration model (fit.h Fit): its scaling and calibrated ranges from the samples, then
// each radiometric model (FitModel, fit.cc), the geometric baseline (fit_geometric.cc), the theta
// correction (fit_theta.cc) and the blur calibration (blur_model.h).
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "base/check.h"
#include "estimator/blur_model.h"
#include "estimator/fit.h"

namespace irdist {
namespace {

// The measured blur of every usable measurement frame, at its true distance.
std::vector<BlurPoint> MeasuredBlur(const std::vector<CalibrationSample>& samples) {
  std::vector<BlurPoint> points;
  for (const CalibrationSample& s : samples) {
    if (!s.measurement.Usable() || !std::isfinite(s.measurement.blur_var_px2)) continue;
    points.push_back({s.d_mm, s.measurement.blur_var_px2});
  }
  return points;
}

// The blob's peak level over the usable frames of the calibration (CalibratedRanges::peak_*).
void RecordPeakRange(const std::vector<CalibrationSample>& samples, CalibratedRanges* r) {
  double lo = std::numeric_limits<double>::infinity(), hi = 0.0;
  for (const CalibrationSample& s : samples) {
    for (const Features* f : {&s.reference, &s.measurement}) {
      if (!f->Usable() || !(f->peak > 0.0)) continue;
      lo = std::min(lo, f->peak);
      hi = std::max(hi, f->peak);
    }
  }
  if (hi > 0.0) {
    r->peak_min = lo;
    r->peak_max = hi;
  }
}

}  // namespace

CalibrationModel Fit(const std::vector<CalibrationSample>& samples,
                     const FeatureOptions& feature_options, const FitOptions& options) {
  std::string why;
  IRDIST_CHECK(options.IsValid(&why), why);
  IRDIST_CHECK(feature_options.IsValid(&why), why);
  CalibrationModel model;
  model.features = feature_options;
  model.scaling = ChooseScaling(samples);
  CalibratedRanges& r = model.ranges;
  r.d_min_mm = r.theta_min_deg = r.t_min_ms = r.t_ref_min_ms = r.bias_min_ma =
      std::numeric_limits<double>::infinity();
  r.d_max_mm = r.theta_max_deg = r.t_max_ms = r.t_ref_max_ms = r.bias_max_ma =
      -std::numeric_limits<double>::infinity();
  for (const CalibrationSample& s : samples) {
    r.d_min_mm = std::min(r.d_min_mm, s.d_mm);
    r.d_max_mm = std::max(r.d_max_mm, s.d_mm);
    r.theta_min_deg = std::min(r.theta_min_deg, s.theta_deg);
    r.theta_max_deg = std::max(r.theta_max_deg, s.theta_deg);
    r.t_min_ms = std::min(r.t_min_ms, s.t_ms);
    r.t_max_ms = std::max(r.t_max_ms, s.t_ms);
    r.t_ref_min_ms = std::min(r.t_ref_min_ms, s.t_ref_ms);
    r.t_ref_max_ms = std::max(r.t_ref_max_ms, s.t_ref_ms);
    r.bias_min_ma = std::min(r.bias_min_ma, s.bias_ma);
    r.bias_max_ma = std::max(r.bias_max_ma, s.bias_ma);
  }
  RecordPeakRange(samples, &r);
  for (ModelKind kind : options.models) {
    const ModelForm form = (kind == ModelKind::kFreeE || kind == ModelKind::kFreeSigma)
                               ? options.free_form
                               : ModelForm::kFull;
    model.models.push_back(FitModel(kind, form, samples, model.scaling, options));
  }
  model.geometric = FitGeometric(samples, options.geometric_blur_varies_with_distance);
  if (options.fit_theta_correction) {
    model.theta_correction =
        FitThetaCorrection(samples, model.geometric, options.theta_correction_degree);
  }
  model.blur_calibration = FitBlurCalibration(MeasuredBlur(samples));
  return model;
}

}  // namespace irdist
