// The geometric baseline (fit.h GeometricModel): the blob's size against 1/d^2 with a blur
// quadratic in 1/d, fitted by linear least squares, with its per-frame noise law.
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "estimator/blur_model.h"
#include "estimator/fit.h"

namespace irdist {

double GeometricModel::DistanceSeMm(double major_var_px2, double se_px2) const {
  return 0.5 * std::fabs(DistanceMm(major_var_px2 - se_px2) - DistanceMm(major_var_px2 + se_px2));
}

namespace {

// The residuals' rms at each calibrated distance (groups of >= 3 samples), then
// ln rms = ln c + k ln(d / 1000 mm) by least squares weighted by the group sizes. With one
// distance only, k = 0 and c = that rms.
void FitGeometricNoise(const std::vector<std::pair<double, double>>& points, GeometricModel* g) {
  std::map<double, std::pair<double, int>> groups;  // D -> (sum of r^2, count)
  for (size_t i = 0; i < points.size(); ++i) {
    const double r = g->summary.residuals[i];
    if (!std::isfinite(r)) continue;
    auto& acc = groups[points[i].first];
    acc.first += r * r;
    ++acc.second;
  }
  std::vector<NoiseGroup> noise_groups;
  for (const auto& [big_d, acc] : groups) {
    noise_groups.push_back({std::log(1.0 / std::sqrt(big_d)), acc.first, acc.second});
  }
  FitNoiseLaw(noise_groups, &g->noise_rel_at_1m, &g->noise_exponent);
}

}  // namespace

double GeometricModel::BlurVarPx2(double d_mm) const {
  const double u = 1000.0 / d_mm;
  return beta_px2 + blur_u1_px2 * u + blur_u2_px2 * u * u;
}

double GeometricModel::DistanceMm(double major_var_px2) const {
  const double a = alpha_px2 + blur_u2_px2, b = blur_u1_px2, c = beta_px2 - major_var_px2;
  if (!(a > 0.0)) return std::numeric_limits<double>::quiet_NaN();
  const double disc = b * b - 4.0 * a * c;
  if (!(disc >= 0.0)) return std::numeric_limits<double>::quiet_NaN();
  // The larger root; written without cancellation when b > 0.
  const double u = b > 0.0 ? -2.0 * c / (b + std::sqrt(disc)) : (-b + std::sqrt(disc)) / (2.0 * a);
  return u > 0.0 ? 1000.0 / u : std::numeric_limits<double>::quiet_NaN();
}

namespace {

// Rows of the relative least squares [u^2 s / var, 1 / var, u / var, u^2 / var] . x = 1 for the
// major axis (s = 1) and, when the blur varies with d, the minor axis (s = cos^2 theta).
struct GeometricRows {
  std::vector<std::array<double, 4>> rows;
  std::vector<std::pair<double, double>> major_points;  // (D, major var): residuals, noise model
};

GeometricRows CollectGeometricRows(const std::vector<CalibrationSample>& samples, bool with_minor) {
  GeometricRows g;
  for (const CalibrationSample& s : samples) {
    const Features& f = s.measurement;
    if (!f.blob_found || f.moment_major_var_px2 <= 0.0) continue;
    const double u = 1000.0 / s.d_mm;
    const double v = f.moment_major_var_px2;
    g.major_points.push_back({u * u, v});
    g.rows.push_back({u * u / v, 1.0 / v, u / v, u * u / v});
    if (!with_minor || f.moment_minor_var_px2 <= 0.0) continue;
    const double cos_t = std::cos(s.theta_deg * 3.14159265358979323846 / 180.0);
    const double m = f.moment_minor_var_px2;
    g.rows.push_back({cos_t * cos_t * u * u / m, 1.0 / m, u / m, u * u / m});
  }
  return g;
}

}  // namespace

GeometricModel FitGeometric(const std::vector<CalibrationSample>& samples,
                            bool blur_varies_with_distance) {
  GeometricModel g;
  const GeometricRows data = CollectGeometricRows(samples, blur_varies_with_distance);
  const int unknowns = blur_varies_with_distance ? 4 : 2;
  g.summary.samples = static_cast<int>(data.major_points.size());
  if (data.major_points.size() < 3 || static_cast<int>(data.rows.size()) < 2 * unknowns) {
    g.summary.message = "fewer than 3 samples with a blob";
    return g;
  }
  Eigen::MatrixXd a(data.rows.size(), unknowns);
  for (size_t i = 0; i < data.rows.size(); ++i) {
    for (int k = 0; k < unknowns; ++k) a(i, k) = data.rows[i][k];
  }
  const Eigen::VectorXd x = a.colPivHouseholderQr().solve(Eigen::VectorXd::Ones(a.rows()));
  g.alpha_px2 = x(0);
  g.beta_px2 = x(1);
  if (blur_varies_with_distance) {
    g.blur_u1_px2 = x(2);
    g.blur_u2_px2 = x(3);
  }
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(a);
  g.summary.condition_number =
      svd.singularValues()(0) / svd.singularValues()(svd.singularValues().size() - 1);
  for (const auto& p : data.major_points) {
    // Relative error of the distance it implies.
    const double d_true = 1000.0 / std::sqrt(p.first);
    const double d_est = g.DistanceMm(p.second);
    g.summary.residuals.push_back(std::isfinite(d_est) ? d_est / d_true - 1.0 : -1.0);
  }
  g.summary.SetErrorsFromResiduals();
  FitGeometricNoise(data.major_points, &g);
  g.summary.termination =
      g.alpha_px2 > 0.0 ? FitSummary::Termination::kConverged : FitSummary::Termination::kFailed;
  g.summary.message = blur_varies_with_distance
                          ? "linear least squares, blur quadratic in 1/d; residuals are relative "
                            "distance errors"
                          : "linear least squares; residuals are relative distance errors";
  return g;
}

}  // namespace irdist
