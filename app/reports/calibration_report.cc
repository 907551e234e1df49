#include "app/reports/calibration_report.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>

#include "app/reports/report.h"
#include "estimator/models.h"

namespace irdist {
namespace {

void Normalise(double poly[4]) {
  double norm = 0.0;
  for (int k = 0; k < 4; ++k) norm += poly[k] * poly[k];
  norm = std::sqrt(norm);
  if (norm > 0.0) {
    for (int k = 0; k < 4; ++k) poly[k] /= norm;
  }
}

}  // namespace

std::vector<CalibrationPoint> CalibrationPointsOf(const CalibrationModel& model,
                                                  const std::vector<CalibrationSample>& samples,
                                                  int eq25_curves) {
  std::vector<CalibrationPoint> points;
  const FittedModel* free_e = model.Find(ModelKind::kFreeE);
  const FittedModel* free_s = model.Find(ModelKind::kFreeSigma);
  if (free_e == nullptr || free_s == nullptr) return points;
  const size_t stride =
      eq25_curves > 0 ? std::max<size_t>(1, samples.size() / static_cast<size_t>(eq25_curves)) : 0;
  for (size_t i = 0; i < samples.size(); ++i) {
    const CalibrationSample& s = samples[i];
    if (!s.reference.Usable() || !s.measurement.Usable()) continue;
    CalibrationPoint p;
    p.d_mm = s.d_mm;
    p.theta_deg = s.theta_deg;
    p.bias_ma = s.bias_ma;
    p.dt_ms = s.t_ms - s.t_ref_ms;
    ModelInputs in;
    in.d_mm = s.d_mm;
    in.theta_deg = s.theta_deg;
    in.bias_ma = s.bias_ma;
    in.dt_ms = p.dt_ms;
    in.df = s.measurement.f00 - s.reference.f00;
    p.de_measured = s.measurement.e_rel - s.reference.e_rel;
    p.ds_measured = s.measurement.sigma - s.reference.sigma;
    p.de_model = free_e->Predict(model.scaling, in);
    p.ds_model = free_s->Predict(model.scaling, in);
    if (stride > 0 && i % stride == 0 && static_cast<int>(i / stride) < eq25_curves) {
      // Eq. 25 (c - a) as a function of d at the true theta, each polynomial normalised.
      std::array<double, kNumModelVars> vars = ScaleInputs(in, model.scaling);
      double a[4], c[4];
      vars[kVarRho] = Rho(s.theta_deg, free_s->sigma_deg);
      AlgebraicPolynomialInD(GetModelSpec(ModelKind::kFreeSigma), free_s->coefficients.data(),
                             vars.data(), p.ds_measured, c);
      vars[kVarRho] = Rho(s.theta_deg, free_e->sigma_deg);
      AlgebraicPolynomialInD(GetModelSpec(ModelKind::kFreeE), free_e->coefficients.data(),
                             vars.data(), p.de_measured, a);
      Normalise(a);
      Normalise(c);
      const double d_lo = 0.8 * model.ranges.d_min_mm, d_hi = 1.2 * model.ranges.d_max_mm;
      for (int k = 0; k <= 60; ++k) {
        const double d_mm = d_lo + (d_hi - d_lo) * k / 60.0;
        const double x = model.scaling.ScaledD(d_mm);
        double value = 0.0;
        for (int j = 3; j >= 0; --j) value = value * x + (c[j] - a[j]);
        p.eq25_d_mm.push_back(d_mm);
        p.eq25_value.push_back(value);
      }
    }
    points.push_back(std::move(p));
  }
  return points;
}

std::string WriteCalibrationReport(const std::string& recording_dir,
                                   const std::vector<CalibrationSample>& samples,
                                   const CalibrationModel& model, const std::string& model_path,
                                   const std::string& report_dir) {
  std::ostringstream text;
  text << "Calibration from " << recording_dir << "\n"
       << model.BriefReport() << "\n"
       << model.fitness.BriefReport() << "\n";
  return WriteReport(report_dir, "irdist calibration",
                     CalibrationReportFields(recording_dir, model_path, model), text.str(),
                     CalibrationPlots(CalibrationPointsOf(model, samples), model));
}

CalibrationReportDrawer CalibrationReportDrawerInto(const std::string& report_dir,
                                                    const std::string& recording_dir) {
  return [report_dir, recording_dir](const CalibrationModel& model,
                                     const std::vector<CalibrationSample>& samples,
                                     const std::string& model_path) {
    return WriteCalibrationReport(recording_dir, samples, model, model_path, report_dir);
  };
}

}  // namespace irdist
