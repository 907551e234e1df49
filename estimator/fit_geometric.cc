// The geometric baseline (fit.h GeometricModel): the blob's size against 1/d^2 with a blur
// polynomial in 1/d (quadratic, or cubic from 4 calibrated distances on) and the size's tilt term
// (fit_tilt.h), fitted by linear least squares, with its per-frame noise law.
#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <iomanip>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "estimator/blur_model.h"
#include "estimator/fit.h"
#include "estimator/fit_tilt.h"
#include "estimator/polynomial_roots.h"

namespace irdist {

double GeometricModel::DistanceSeMm(double major_var_px2, double se_px2) const {
  return 0.5 * std::fabs(DistanceMm(major_var_px2 - se_px2) - DistanceMm(major_var_px2 + se_px2));
}

namespace {

// The cubic law's unknowns: alpha, beta and the blur's three terms in u. It is taken wherever the
// calibration has kCubicMinDistances distances of 3 or more frames: a lens of the quadratic's
// family loses a little noise between the distances, one outside it (a defocus disc's PSF, a halo)
// keeps no bias at them; a chi-square test of the quadratic's misfit could not tell the two apart
// (its se holds the sizes' dependence on theta: docs/estimator.md "Geometric baseline").
constexpr int kCubicUnknowns = 5;
constexpr int kCubicMinDistances = 4;

// The major axis's residuals (relative distance errors) at each calibrated distance: their count,
// sum and sum of squares, by D = u^2; non-finite ones left out.
struct ResidualGroup {
  int count = 0;
  double sum = 0.0, sum2 = 0.0;
};
std::map<double, ResidualGroup> GroupByDistance(
    const std::vector<std::pair<double, double>>& points, const std::vector<double>& residuals) {
  std::map<double, ResidualGroup> groups;
  for (size_t i = 0; i < points.size(); ++i) {
    const double r = residuals[i];
    if (!std::isfinite(r)) continue;
    ResidualGroup& group = groups[points[i].first];
    ++group.count;
    group.sum += r;
    group.sum2 += r * r;
  }
  return groups;
}

// The residuals' rms at each calibrated distance (groups of >= 3 samples), then
// ln rms = ln c + k ln(d / 1000 mm) by least squares weighted by the group sizes. With one
// distance only, k = 0 and c = that rms.
void FitGeometricNoise(const std::vector<std::pair<double, double>>& points, GeometricModel* g) {
  std::vector<NoiseGroup> noise_groups;
  for (const auto& [big_d, group] : GroupByDistance(points, g->summary.residuals)) {
    noise_groups.push_back({std::log(1.0 / std::sqrt(big_d)), group.sum2, group.count});
  }
  FitNoiseLaw(noise_groups, &g->noise_rel_at_1m, &g->noise_exponent);
}

}  // namespace

double GeometricModel::BlurVarPx2(double d_mm) const {
  const double u = 1000.0 / d_mm;
  return beta_px2 + (blur_u1_px2 + (blur_u2_px2 + blur_u3_px2 * u) * u) * u;
}

namespace {

// The larger root u of a u^2 + b u + c = 0; NaN when none. Written without cancellation when
// b > 0.
double QuadraticRoot(double a, double b, double c) {
  if (!(a > 0.0)) return std::numeric_limits<double>::quiet_NaN();
  const double disc = b * b - 4.0 * a * c;
  if (!(disc >= 0.0)) return std::numeric_limits<double>::quiet_NaN();
  return b > 0.0 ? -2.0 * c / (b + std::sqrt(disc)) : (-b + std::sqrt(disc)) / (2.0 * a);
}

// The root u > 0 of poly (ascending, cubic) where the law rises with u (the size grows as the
// disc comes closer), nearest `near` when there are several; NaN when none.
double RisingCubicRoot(const double poly[4], double near) {
  double roots[3];
  const int n = RealRoots(poly, roots);
  double best = std::numeric_limits<double>::quiet_NaN();
  for (int i = 0; i < n; ++i) {
    const double u = roots[i];
    const double slope = poly[1] + (2.0 * poly[2] + 3.0 * poly[3] * u) * u;
    if (!(u > 0.0) || !(slope > 0.0)) continue;
    if (!std::isfinite(best) || std::fabs(u - near) < std::fabs(best - near)) best = u;
  }
  return best;
}

}  // namespace

double GeometricModel::DistanceMm(double major_var_px2) const {
  const double a = alpha_px2 + blur_u2_px2, b = blur_u1_px2, c = beta_px2 - major_var_px2;
  double u = QuadraticRoot(a, b, c);
  if (blur_u3_px2 != 0.0 && std::isfinite(u)) {
    const double poly[4] = {c, b, a, blur_u3_px2};
    u = RisingCubicRoot(poly, u);
  }
  return u > 0.0 ? 1000.0 / u : std::numeric_limits<double>::quiet_NaN();
}

namespace {

// Rows of the relative least squares [u^2 s / var, 1 / var, u / var, u^2 / var, u^3 / var] . x = 1
// for the major axis (s = 1) and, when the blur varies with d, the minor axis (s = cos^2 theta).
struct GeometricRows {
  std::vector<std::array<double, 5>> rows;
  std::vector<std::pair<double, double>> major_points;  // (D, major var): residuals, noise model
};

// The major axis's variance less `law`'s tilt term (none before it is fitted).
GeometricRows CollectGeometricRows(const std::vector<CalibrationSample>& samples, bool with_minor,
                                   const GeometricModel& law) {
  GeometricRows g;
  for (const CalibrationSample& s : samples) {
    const Features& f = s.measurement;
    const double v = law.FrameMajorVarPx2(f);
    if (!f.blob_found || !(v > 0.0)) continue;  // T is 0 where the size is not > 0
    const double u = 1000.0 / s.d_mm;
    g.major_points.push_back({u * u, v});
    g.rows.push_back({u * u / v, 1.0 / v, u / v, u * u / v, u * u * u / v});
    if (!with_minor || f.moment_minor_var_px2 <= 0.0) continue;
    const double cos_t = std::cos(s.theta_deg * 3.14159265358979323846 / 180.0);
    const double m = f.moment_minor_var_px2;
    g.rows.push_back({cos_t * cos_t * u * u / m, 1.0 / m, u / m, u * u / m, u * u * u / m});
  }
  return g;
}

// The least squares with the first `unknowns` columns, into g: its coefficients, condition number
// and the major axis's residuals as relative distance errors.
void SolveGeometric(const GeometricRows& data, int unknowns, GeometricModel* g) {
  Eigen::MatrixXd a(data.rows.size(), unknowns);
  for (size_t i = 0; i < data.rows.size(); ++i) {
    for (int k = 0; k < unknowns; ++k) a(i, k) = data.rows[i][k];
  }
  const Eigen::VectorXd x = a.colPivHouseholderQr().solve(Eigen::VectorXd::Ones(a.rows()));
  g->alpha_px2 = x(0);
  g->beta_px2 = x(1);
  g->blur_u1_px2 = unknowns > 2 ? x(2) : 0.0;
  g->blur_u2_px2 = unknowns > 3 ? x(3) : 0.0;
  g->blur_u3_px2 = unknowns > 4 ? x(4) : 0.0;
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(a);
  g->summary.condition_number =
      svd.singularValues()(0) / svd.singularValues()(svd.singularValues().size() - 1);
  g->summary.residuals.clear();
  for (const auto& p : data.major_points) {
    const double d_true = 1000.0 / std::sqrt(p.first);
    const double d_est = g->DistanceMm(p.second);
    g->summary.residuals.push_back(std::isfinite(d_est) ? d_est / d_true - 1.0 : -1.0);
  }
}

// The law's misfit against the frames' noise: each calibrated distance's mean residual over its
// standard error (the frames' scatter there over sqrt(n)), squared and summed over the distances
// of 3 or more frames. *distances: how many.
double MisfitChi2(const GeometricRows& data, const std::vector<double>& residuals, int* distances) {
  double chi2 = 0.0;
  *distances = 0;
  for (const auto& [big_d, group] : GroupByDistance(data.major_points, residuals)) {
    if (group.count < 3) continue;
    const double n = group.count, mean = group.sum / n;
    const double var = std::max((group.sum2 - n * mean * mean) / (n - 1.0), 1e-300);
    chi2 += mean * mean / (var / n);
    ++*distances;
  }
  return chi2;
}

}  // namespace

GeometricModel FitGeometric(const std::vector<CalibrationSample>& samples,
                            bool blur_varies_with_distance) {
  GeometricModel g;
  GeometricRows data = CollectGeometricRows(samples, blur_varies_with_distance, g);
  const int unknowns = blur_varies_with_distance ? 4 : 2;
  g.summary.samples = static_cast<int>(data.major_points.size());
  if (data.major_points.size() < 3 || static_cast<int>(data.rows.size()) < 2 * unknowns) {
    g.summary.message = "fewer than 3 samples with a blob";
    return g;
  }
  SolveGeometric(data, unknowns, &g);
  std::string law = blur_varies_with_distance ? "blur quadratic in 1/d" : "a fixed blur";
  double chi2 = 0.0;
  int distances = 0;
  int solved = unknowns;
  if (blur_varies_with_distance) chi2 = MisfitChi2(data, g.summary.residuals, &distances);
  if (distances >= kCubicMinDistances && static_cast<int>(data.rows.size()) >= 2 * kCubicUnknowns) {
    solved = kCubicUnknowns;
    SolveGeometric(data, solved, &g);
    std::ostringstream text;
    text << "blur cubic in 1/d (" << distances << " distances; the quadratic's misfit chi2 "
         << std::setprecision(3) << chi2 << ")";
    law = text.str();
  }
  // The tilt term from this law's departures, then the law again on the sizes less it.
  const std::string tilt = FitTiltTerm(samples, &g);
  if (!tilt.empty()) {
    data = CollectGeometricRows(samples, blur_varies_with_distance, g);
    SolveGeometric(data, solved, &g);
    law += "; " + tilt;
  }
  g.summary.SetErrorsFromResiduals();
  FitGeometricNoise(data.major_points, &g);
  g.summary.termination =
      g.alpha_px2 > 0.0 ? FitSummary::Termination::kConverged : FitSummary::Termination::kFailed;
  g.summary.message = "linear least squares, " + law + "; residuals are relative distance errors";
  return g;
}

}  // namespace irdist
