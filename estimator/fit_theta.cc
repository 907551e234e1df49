// The calibrated theta correction (fit.h ThetaCorrection): cos^2(theta) as a polynomial of the
// blob's squared axis ratio (blur removed) and its distance, fitted on the calibration's frames.
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/Dense>

#include "base/check.h"
#include "estimator/fit.h"

namespace irdist {
namespace {

// Monomials of total degree <= `degree` in (x, z), graded order (ThetaCorrection).
int ThetaBasis(int degree, double x, double z, double* out) {
  int n = 0;
  for (int total = 0; total <= degree; ++total) {
    for (int zp = 0; zp <= total; ++zp) {
      out[n++] = std::pow(x, total - zp) * std::pow(z, zp);
    }
  }
  return n;
}

// x = (minor - beta) / (major - beta) and the geometric distance (mm); false without a blob
// larger than the blur.
bool RatioAndDistance(double major, double minor, const GeometricModel& g, double* x,
                      double* d_mm) {
  if (!(g.alpha_px2 > 0.0)) return false;
  *d_mm = g.DistanceMm(major);
  if (!std::isfinite(*d_mm)) return false;
  const double blur = g.BlurVarPx2(*d_mm);
  const double a = major - blur;
  if (!(a > 0.0)) return false;
  *x = std::clamp(std::max(0.0, minor - blur) / a, 0.0, 1.0);
  return true;
}

}  // namespace

double ThetaCorrection::ThetaDeg(double major_var_px2, double minor_var_px2,
                                 const GeometricModel& g) const {
  double x, d_mm;
  if (!RatioAndDistance(major_var_px2, minor_var_px2, g, &x, &d_mm)) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  double cos2 = x;
  if (fitted()) {
    x = std::clamp(x, ratio_sq_min, ratio_sq_max);
    const double half = 0.5 * (d_max_mm - d_min_mm);
    const double z = half > 0.0 ? (std::clamp(d_mm, d_min_mm, d_max_mm) - d_min_mm) / half - 1.0
                                : 0.0;
    double basis[10];
    const int n = ThetaBasis(degree, x, z, basis);
    IRDIST_CHECK(static_cast<int>(coefficients.size()) == n, "theta correction of degree ", degree,
                 " needs ", n, " coefficients, has ", coefficients.size());
    cos2 = 0.0;
    for (int k = 0; k < n; ++k) cos2 += coefficients[k] * basis[k];
  }
  return std::acos(std::sqrt(std::clamp(cos2, 0.0, 1.0))) * 180.0 / 3.14159265358979323846;
}

namespace {

// One usable calibration frame of the theta correction: its squared axis ratio x, geometric
// distance and true theta.
struct ThetaFrame {
  double x, d_mm, theta_deg;
};

std::vector<ThetaFrame> ThetaFrames(const std::vector<CalibrationSample>& samples,
                                    const GeometricModel& geometric) {
  std::vector<ThetaFrame> frames;
  if (!geometric.fitted()) return frames;
  for (const CalibrationSample& s : samples) {
    const Features& m = s.measurement;
    if (!m.Usable()) continue;
    ThetaFrame f{0.0, 0.0, s.theta_deg};
    if (RatioAndDistance(m.moment_major_var_px2, m.moment_minor_var_px2, geometric, &f.x,
                         &f.d_mm)) {
      frames.push_back(f);
    }
  }
  return frames;
}

// The calibrated ranges of x and of the geometric distance.
void SetThetaRanges(const std::vector<ThetaFrame>& frames, ThetaCorrection* tc) {
  tc->ratio_sq_min = tc->d_min_mm = std::numeric_limits<double>::infinity();
  tc->ratio_sq_max = tc->d_max_mm = -std::numeric_limits<double>::infinity();
  for (const ThetaFrame& f : frames) {
    tc->ratio_sq_min = std::min(tc->ratio_sq_min, f.x);
    tc->ratio_sq_max = std::max(tc->ratio_sq_max, f.x);
    tc->d_min_mm = std::min(tc->d_min_mm, f.d_mm);
    tc->d_max_mm = std::max(tc->d_max_mm, f.d_mm);
  }
}

// The weighted least-squares system a c = y of cos^2(theta) in the basis of tc's degree.
void ThetaSystem(const std::vector<ThetaFrame>& frames, const ThetaCorrection& tc,
                 Eigen::MatrixXd* a, Eigen::VectorXd* y) {
  const int terms = ThetaCorrection::NumTerms(tc.degree);
  const double half = 0.5 * (tc.d_max_mm - tc.d_min_mm);
  a->resize(frames.size(), terms);
  y->resize(frames.size());
  for (size_t i = 0; i < frames.size(); ++i) {
    const double z = half > 0.0 ? (frames[i].d_mm - tc.d_min_mm) / half - 1.0 : 0.0;
    double basis[10];
    ThetaBasis(tc.degree, frames[i].x, z, basis);
    for (int k = 0; k < terms; ++k) (*a)(i, k) = basis[k];
    // Rows at theta >= 10 deg weighted by 1 / (d cos^2 / d theta) = 1 / sin(2 theta): their
    // residuals are then theta errors (rad). Nearly round blobs (theta < 10 deg: the eigenvalue
    // noise floor dominates their axis ratio) get a small constant weight, so that they do not
    // bend the fit at the angles where theta is observable.
    const double th = frames[i].theta_deg * 3.14159265358979323846 / 180.0;
    const double w = frames[i].theta_deg >= 10.0 ? 1.0 / std::sin(2.0 * th) : 0.25;
    const double c = std::cos(th);
    (*y)(i) = c * c * w;
    a->row(i) *= w;
  }
}

// Corrected minus true theta (deg) of every usable calibration frame, and the errors.
void FillThetaResiduals(const std::vector<CalibrationSample>& samples,
                        const GeometricModel& geometric, ThetaCorrection* tc) {
  for (const CalibrationSample& s : samples) {
    const Features& m = s.measurement;
    if (!m.Usable()) continue;
    const double t = tc->ThetaDeg(m.moment_major_var_px2, m.moment_minor_var_px2, geometric);
    if (std::isfinite(t)) tc->summary.residuals.push_back(t - s.theta_deg);
  }
  tc->summary.SetErrorsFromResiduals();
}

}  // namespace

ThetaCorrection FitThetaCorrection(const std::vector<CalibrationSample>& samples,
                                   const GeometricModel& geometric, int degree) {
  IRDIST_CHECK(degree >= 1 && degree <= 3, "theta correction degree ", degree, " not in [1, 3]");
  ThetaCorrection tc;
  const std::vector<ThetaFrame> frames = ThetaFrames(samples, geometric);
  const int terms = ThetaCorrection::NumTerms(degree);
  tc.summary.samples = static_cast<int>(frames.size());
  if (!geometric.fitted() || static_cast<int>(frames.size()) < 2 * terms) {
    tc.summary.message = geometric.fitted() ? "too few usable frames for the theta correction"
                                            : "no geometric model (blur variance) to correct";
    return tc;
  }
  tc.degree = degree;
  SetThetaRanges(frames, &tc);
  Eigen::MatrixXd a;
  Eigen::VectorXd y;
  ThetaSystem(frames, tc, &a, &y);
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const Eigen::VectorXd sv = svd.singularValues();
  tc.summary.condition_number = sv(sv.size() - 1) > 0.0 ? sv(0) / sv(sv.size() - 1)
                                                        : std::numeric_limits<double>::infinity();
  if (!(sv(sv.size() - 1) > 1e-12 * sv(0))) {
    tc.summary.message = "rank-deficient: the calibration needs several angles and distances";
    tc.degree = 0;
    return tc;
  }
  const Eigen::VectorXd c = svd.solve(y);
  tc.coefficients.assign(c.data(), c.data() + c.size());
  FillThetaResiduals(samples, geometric, &tc);
  tc.summary.termination = FitSummary::Termination::kConverged;
  tc.summary.message =
      "linear least squares of cos^2(theta); residuals are theta errors in degrees";
  return tc;
}

}  // namespace irdist
