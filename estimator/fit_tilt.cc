// The size law's tilt term: its evaluation and its fit (fit_tilt.h).
#include "estimator/fit_tilt.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <map>
#include <sstream>

#include "estimator/disc_fit.h"

namespace irdist {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The piecewise-linear basis at theta_deg: the two knots around it and their weights; the end
// knot alone beyond the ends.
struct HatWeights {
  int lo = 0, hi = 0;
  double w_lo = 1.0, w_hi = 0.0;
};
HatWeights HatAt(const std::vector<double>& knots, double theta_deg) {
  HatWeights h;
  const int n = static_cast<int>(knots.size());
  if (theta_deg <= knots.front()) return h;
  if (theta_deg >= knots.back()) {
    h.lo = h.hi = n - 1;
    return h;
  }
  const int hi =
      static_cast<int>(std::upper_bound(knots.begin(), knots.end(), theta_deg) - knots.begin());
  h.lo = hi - 1;
  h.hi = hi;
  h.w_hi = (theta_deg - knots[h.lo]) / (knots[h.hi] - knots[h.lo]);
  h.w_lo = 1.0 - h.w_hi;
  return h;
}

// One frame of the fit: its calibrated angle, its own theta, its departure from the law (px^2)
// and its weight.
struct TiltPoint {
  double calibrated_deg, theta_deg, residual_px2, weight;
};

// The frames with a blob fit (their own theta) and a standard error of their size.
std::vector<TiltPoint> TiltPoints(const std::vector<CalibrationSample>& samples,
                                  const GeometricModel& g) {
  std::vector<TiltPoint> points;
  for (const CalibrationSample& s : samples) {
    const Features& f = s.measurement;
    const double theta = FrameDiscThetaDeg(f);
    const double se = f.major_var_se_px2;
    if (!f.blob_found || !std::isfinite(theta) || !(se > 0.0) || !std::isfinite(se)) continue;
    points.push_back({std::fabs(s.theta_deg), theta, f.moment_major_var_px2 - g.MajorVarPx2(s.d_mm),
                      1.0 / (se * se)});
  }
  return points;
}

// The calibrated angles with kMinTiltKnotFrames points or more.
std::vector<double> TiltKnots(const std::vector<TiltPoint>& points) {
  std::map<double, int> counts;
  for (const TiltPoint& p : points) ++counts[p.calibrated_deg];
  std::vector<double> knots;
  for (const auto& [theta, n] : counts) {
    if (n >= kMinTiltKnotFrames) knots.push_back(theta);
  }
  return knots;
}

// Least squares of the points on the basis; each knot's value shrunk by its noise. False when
// the system is singular.
bool SolveTilt(const std::vector<double>& knots, const std::vector<TiltPoint>& points,
               std::vector<double>* values) {
  const int n = static_cast<int>(knots.size());
  std::vector<HatWeights> hats;
  hats.reserve(points.size());
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(n);
  for (const TiltPoint& p : points) {
    const HatWeights& h = hats.emplace_back(HatAt(knots, p.theta_deg));
    const int idx[2] = {h.lo, h.hi};
    const double w[2] = {h.w_lo, h.w_hi};
    for (int i = 0; i < 2; ++i) {
      b(idx[i]) += p.weight * w[i] * p.residual_px2;
      for (int j = 0; j < 2; ++j) a(idx[i], idx[j]) += p.weight * w[i] * w[j];
    }
  }
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(a);
  if (ldlt.info() != Eigen::Success || !(ldlt.rcond() > 1e-12)) return false;
  const Eigen::VectorXd t = ldlt.solve(b);
  double chi2 = 0.0;
  for (size_t i = 0; i < points.size(); ++i) {
    const HatWeights& h = hats[i];
    const double r = points[i].residual_px2 - h.w_lo * t(h.lo) - h.w_hi * t(h.hi);
    chi2 += points[i].weight * r * r;
  }
  const double dof = static_cast<double>(points.size()) - n;
  const double scale = dof > 0.0 ? std::max(1.0, chi2 / dof) : 1.0;  // a misfit widens the se
  const Eigen::MatrixXd cov = ldlt.solve(Eigen::MatrixXd::Identity(n, n)) * scale;
  values->assign(n, 0.0);
  for (int k = 0; k < n; ++k) {
    const double t2 = t(k) * t(k);
    const double keep = t2 > 0.0 ? 1.0 - cov(k, k) / t2 : 0.0;
    (*values)[k] = keep > 0.0 ? t(k) * keep : 0.0;  // +0 where shrunk away
  }
  return t.allFinite();
}

}  // namespace

double FrameDiscThetaDeg(const Features& f) {
  if (!std::isfinite(f.size_blur_var_px2)) return kNaN;
  return Theta0FromVariances(f.moment_minor_var_px2 - f.size_blur_var_px2,
                             f.moment_major_var_px2 - f.size_blur_var_px2);
}

double GeometricModel::TiltVarPx2(double theta_deg) const {
  if (tilt_theta_deg.empty() || !std::isfinite(theta_deg)) return 0.0;
  const HatWeights h = HatAt(tilt_theta_deg, std::fabs(theta_deg));
  return h.w_lo * tilt_var_px2[h.lo] + h.w_hi * tilt_var_px2[h.hi];
}

double GeometricModel::FrameMajorVarPx2(const Features& f) const {
  return f.moment_major_var_px2 - TiltVarPx2(FrameDiscThetaDeg(f));
}

std::string FitTiltTerm(const std::vector<CalibrationSample>& samples, GeometricModel* g) {
  g->tilt_theta_deg.clear();
  g->tilt_var_px2.clear();
  const std::vector<TiltPoint> points = TiltPoints(samples, *g);
  const std::vector<double> knots = TiltKnots(points);
  if (static_cast<int>(knots.size()) < kMinTiltKnots) return "";
  std::vector<double> values;
  if (!SolveTilt(knots, points, &values)) return "";
  const auto largest = std::max_element(
      values.begin(), values.end(), [](double x, double y) { return std::fabs(x) < std::fabs(y); });
  if (*largest == 0.0) return "";
  g->tilt_theta_deg = knots;
  g->tilt_var_px2 = values;
  std::ostringstream text;
  text << "tilt term over " << knots.size() << " angles (largest " << std::setprecision(3)
       << *largest << " px^2 at " << knots[largest - values.begin()] << " deg)";
  return text.str();
}

}  // namespace irdist
