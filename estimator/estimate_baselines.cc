#include "estimator/estimate_baselines.h"

#include <array>
#include <cmath>
#include <sstream>

#include "base/check.h"
#include "estimator/models.h"

namespace irdist {

std::string GeometricEstimate::BriefReport() const {
  if (!valid) return "geometric: no estimate (no blob or size below the calibrated blur)";
  std::ostringstream out;
  out << "geometric: d = " << d_mm << " mm" << (outside_calibrated_range ? " (OUTSIDE RANGE)" : "");
  return out.str();
}

GeometricEstimate EstimateGeometric(const CalibrationModel& model, const Features& features) {
  GeometricEstimate out;
  const GeometricModel& g = model.geometric;
  IRDIST_CHECK(g.fitted(), "the model has no fitted geometric baseline");
  if (!features.blob_found) return out;
  const double d_mm = g.DistanceMm(g.FrameMajorVarPx2(features));
  if (!std::isfinite(d_mm)) return out;
  out.valid = true;
  out.d_mm = d_mm;
  out.outside_calibrated_range =
      out.d_mm < model.ranges.d_min_mm || out.d_mm > model.ranges.d_max_mm;
  return out;
}

std::string I0DependentEstimate::BriefReport() const {
  if (!valid) return "i0_dependent: no estimate";
  std::ostringstream out;
  out << "i0_dependent: d = " << d_mm << " mm at an assumed " << assumed_bias_ma
      << " mA, theta = " << theta_deg << " deg (ellipse)"
      << (outside_calibrated_range ? " (OUTSIDE RANGE)" : "");
  return out.str();
}

I0DependentEstimate EstimateI0Dependent(const CalibrationModel& model, const Features& reference,
                                        double t_ref_ms, const std::vector<Features>& measurements,
                                        const std::vector<double>& t_ms, double assumed_bias_ma) {
  IRDIST_CHECK(measurements.size() == t_ms.size(), "measurements and t_ms differ in length");
  I0DependentEstimate out;
  out.assumed_bias_ma = assumed_bias_ma;
  const FittedModel* f = model.Find(ModelKind::kDiffF);
  if (f == nullptr || f->coefficients.empty() || !reference.blob_found) return out;
  const ModelSpec& spec = GetModelSpec(ModelKind::kDiffF);
  // dF = u + v D at fixed theta: least squares of (u + v D) / y - 1 over the bracket.
  double num = 0.0, den = 0.0, theta = 0.0;
  int n = 0;
  for (size_t i = 0; i < measurements.size(); ++i) {
    const Features& m = measurements[i];
    if (!m.blob_found) continue;
    theta += m.theta0_deg;
    ++n;
  }
  if (n == 0) return out;
  theta /= n;
  for (size_t i = 0; i < measurements.size(); ++i) {
    const Features& m = measurements[i];
    if (!m.blob_found) continue;
    ModelInputs in;
    in.bias_ma = assumed_bias_ma;
    in.dt_ms = t_ms[i] - t_ref_ms;
    in.theta_deg = theta;
    std::array<double, kNumModelVars> vars = ScaleInputs(in, model.scaling);
    vars[kVarRho] = Rho(theta, f->sigma_deg);
    vars[kVarD] = 0.0;
    const double u = EvaluateModel(spec, f->coefficients.data(), vars.data());
    vars[kVarD] = 1.0;
    const double v = EvaluateModel(spec, f->coefficients.data(), vars.data()) - u;
    const double y = m.f00 - reference.f00;
    if (!(std::abs(y) > 0.0)) continue;
    num += (v / y) * (1.0 - u / y);
    den += (v / y) * (v / y);
  }
  if (!(den > 0.0) || !(num / den > 0.0)) return out;
  out.valid = true;
  out.d_mm = model.scaling.DistanceFromScaledD(num / den);
  out.theta_deg = theta;
  out.outside_calibrated_range =
      out.d_mm < model.ranges.d_min_mm || out.d_mm > model.ranges.d_max_mm;
  return out;
}

}  // namespace irdist
