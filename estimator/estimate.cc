#include "estimator/estimate.h"

#include <ceres/jet.h>
#include <ceres/tiny_solver.h>

#include <Eigen/Dense>
#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>
#include <complex>
#include <limits>
#include <sstream>
#include <unsupported/Eigen/Polynomials>
#include <utility>

#include "base/check.h"
#include "base/pi.h"
#include "estimator/polynomial_roots.h"
#include "estimator/round_blob.h"
#include "estimator/theta_start.h"

namespace irdist {
namespace {

constexpr double kRad = kPi / 180.0;

// One measured difference of a bracket, in the models' scaled variables.
struct Difference {
  double dt;  // scaled
  double df;  // scaled
  double de;  // measured dE
  double ds;  // measured dS
};

struct Problem {
  const CalibrationModel* model;
  const FittedModel* e;
  const FittedModel* s;
  bool use_e;
  const Difference* diffs;
  int count;
  // kFused: weights (1 / calibration mean relative error) and the extra equations.
  bool fused = false;
  double e_weight = 1.0;
  double s_weight = 1.0;
  double geo_weight = 0.0;           // 0: no geometric equations
  const double* geo_ln_d = nullptr;  // per difference, ln of the frame's geometric d (NaN: none)
  double ref_geo_ln_d = 0.0;         // the reference frame's (EstimateOptions::reference_size)
  double ref_geo_weight = 0.0;       // 0, or a NaN ln d: no reference equation
  double theta_prior_rad = 0.0;
  double theta_prior_weight = 0.0;  // 1 / sd in rad; 0: no prior
  double huber = 0.0;               // kFused: Huber threshold of the radiometric residuals
  // kFused: the measurement frames' own noise of ln d (rms, from their blob-fit sizes' standard
  // errors: FrameNoiseRel); 0 = the calibration's noise law GeometricModel::NoiseRel(d).
  double frame_noise_rel = 0.0;
};

// The residual whose square is the Huber loss (x2) of r with threshold k: r itself within k,
// sign(r) sqrt(k (2 |r| - k)) beyond (continuous with its first derivative). Jets compare by
// value, so one template serves the solve and its derivatives. ceres::TinySolver takes no loss
// function (ceres::HuberLoss belongs to a ceres::Problem, whose set-up costs more than this
// whole solve), so the loss rides in the residual itself.
template <typename T>
T Robust(const T& r, double k) {
  using std::sqrt;
  if (!(k > 0.0) || (r <= T(k) && r >= T(-k))) return r;
  const bool negative = r < T(0.0);
  const T robust = sqrt(k * (2.0 * (negative ? -r : r) - k));
  return negative ? -robust : robust;
}

// Relative residuals of Eq. 26 at (ln d, theta rad): [E_0, S_0, E_1, S_1, ...] (E left out when
// degenerate). Returns the number of residuals.
template <typename T>
int Residuals(const Problem& p, const T& ln_d, const T& theta_rad, T* r) {
  using std::exp;
  const double r0 = p.model->scaling.d_ref_mm;
  const T d_mm = exp(ln_d);
  const T big_d = (r0 / d_mm) * (r0 / d_mm) / p.model->scaling.d_scale;
  const T theta_deg = theta_rad / kRad;
  int n = 0;
  for (int i = 0; i < p.count; ++i) {
    T vars[kNumModelVars];
    vars[kVarD] = big_d;
    vars[kVarT] = T(0.0);
    vars[kVarI0] = T(0.0);
    vars[kVarDt] = T(p.diffs[i].dt);
    vars[kVarDF] = T(p.diffs[i].df);
    if (p.use_e) {
      vars[kVarRho] = Rho(theta_deg, T(p.e->sigma_deg));
      r[n++] = Robust((EvaluateModel(GetModelSpec(ModelKind::kFreeE), p.e->coefficients.data(),
                                     vars) /
                           p.diffs[i].de -
                       1.0) *
                          p.e_weight,
                      p.huber);
    }
    vars[kVarRho] = Rho(theta_deg, T(p.s->sigma_deg));
    r[n++] = Robust((EvaluateModel(GetModelSpec(ModelKind::kFreeSigma), p.s->coefficients.data(),
                                   vars) /
                         p.diffs[i].ds -
                     1.0) *
                        p.s_weight,
                    p.huber);
  }
  if (p.geo_weight > 0.0) {
    for (int i = 0; i < p.count; ++i) {
      if (std::isfinite(p.geo_ln_d[i])) r[n++] = (ln_d - p.geo_ln_d[i]) * p.geo_weight;
    }
  }
  if (p.ref_geo_weight > 0.0 && std::isfinite(p.ref_geo_ln_d)) {
    r[n++] = (ln_d - p.ref_geo_ln_d) * p.ref_geo_weight;
  }
  if (p.theta_prior_weight > 0.0) r[n++] = (theta_rad - p.theta_prior_rad) * p.theta_prior_weight;
  return n;
}

constexpr int kMaxResiduals = 3 * kMaxBracketExposures + 2;
using Jet2 = ceres::Jet<double, 2>;

// Residuals and Jacobian (columns: ln d, theta rad).
int Linearise(const Problem& p, double ln_d, double theta_rad, double* r, double (*j)[2]) {
  Jet2 rj[kMaxResiduals];
  const int n = Residuals(p, Jet2(ln_d, 0), Jet2(theta_rad, 1), rj);
  for (int i = 0; i < n; ++i) {
    r[i] = rj[i].a;
    j[i][0] = rj[i].v[0];
    j[i][1] = rj[i].v[1];
  }
  return n;
}

// Eq. 26 for ceres::TinySolver: the residuals in (ln d, theta rad), or in ln d alone with theta
// held at its start (kParams 1: theta from the ellipse, the E equation degenerate). Derivatives
// come from the same Residuals template through Jets.
template <int kParams>
struct EstimateCost {
  using Scalar = double;
  enum { NUM_RESIDUALS = Eigen::Dynamic, NUM_PARAMETERS = kParams };

  const Problem* p;
  double theta_fixed_rad;
  int num_residuals;

  int NumResiduals() const { return num_residuals; }

  bool operator()(const double* x, double* r, double* jacobian) const {
    const double theta_rad = kParams == 2 ? x[1] : theta_fixed_rad;
    if (jacobian == nullptr) {
      Residuals(*p, x[0], theta_rad, r);
      return true;
    }
    Jet2 rj[kMaxResiduals];
    const int n = Residuals(*p, Jet2(x[0], 0), Jet2(theta_rad, 1), rj);
    for (int i = 0; i < n; ++i) {
      r[i] = rj[i].a;
      jacobian[i] = rj[i].v[0];  // column-major: the ln d column, then the theta column
      if (kParams == 2) jacobian[n + i] = rj[i].v[1];
    }
    return true;
  }
};

// Runs TinySolver's Levenberg-Marquardt from x = (ln d0, theta0 rad); returns whether it stopped
// on a tolerance (not on the iteration budget) at a finite cost.
template <int kParams>
bool RunTinySolver(const Problem& p, const EstimateOptions& options, double x[2],
                   int* iterations) {
  double r[kMaxResiduals];
  const EstimateCost<kParams> cost{&p, x[1], Residuals(p, x[0], x[1], r)};
  ceres::TinySolver<EstimateCost<kParams>> solver;
  solver.options.max_num_iterations = options.max_iterations + 1;  // it counts from 1
  solver.options.parameter_tolerance = options.step_tolerance;
  solver.options.gradient_tolerance = 1e-30;
  solver.options.function_tolerance = 1e-30;
  solver.options.cost_threshold = 0.5e-30;
  typename ceres::TinySolver<EstimateCost<kParams>>::Parameters params;
  for (int k = 0; k < kParams; ++k) params(k) = x[k];
  const auto& summary = solver.Solve(cost, &params);
  for (int k = 0; k < kParams; ++k) x[k] = params(k);
  *iterations = std::min(summary.iterations, options.max_iterations);  // steps tried
  return summary.status != decltype(solver)::HIT_MAX_ITERATIONS &&
         std::isfinite(summary.final_cost);
}

// Unweighted relative residuals of the model equations alone (rms of E and of Sigma), for the
// report.
void ReportPlainResiduals(const Problem& p, const double x[2], DistanceEstimate* out) {
  Problem plain = p;
  plain.fused = false;
  plain.e_weight = plain.s_weight = 1.0;
  plain.geo_weight = plain.theta_prior_weight = 0.0;
  plain.huber = 0.0;
  double rp[kMaxResiduals];
  const int np = Residuals(plain, x[0], x[1], rp);
  double se = 0.0, ss = 0.0;
  int ne = 0, ns = 0;
  for (int i = 0; i < np; ++i) {
    const bool is_e = p.use_e && (i % 2 == 0);
    (is_e ? se : ss) += rp[i] * rp[i];
    ++(is_e ? ne : ns);
  }
  out->residual_e = ne > 0 ? std::sqrt(se / ne) : 0.0;
  out->residual_sigma = ns > 0 ? std::sqrt(ss / ns) : 0.0;
}

// J^T J at x of the equations and of the theta prior (the last row when there is one) apart: the
// covariance rescales the equations only.
void NormalMatrices(const Problem& p, const double x[2], Eigen::Matrix2d* h_equations,
                    Eigen::Matrix2d* h_prior) {
  double r[kMaxResiduals], j[kMaxResiduals][2];
  const int n = Linearise(p, x[0], x[1], r, j);
  const int equations = n - (p.theta_prior_weight > 0.0 ? 1 : 0);
  h_equations->setZero();
  h_prior->setZero();
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector2d row(j[i][0], j[i][1]);
    (i < equations ? *h_equations : *h_prior) += row * row.transpose();
  }
}

// kFused: residuals are in units of their calibration errors. The equations' rows are rescaled
// from the geometric fit's mean error to the frames' own noise of ln d (their blob-fit sizes'
// standard errors) or, without it, to the calibration's noise law at this d (one factor for all:
// their ratios stay as weighted); the theta prior's row keeps its own sd. Then the covariance is
// (J^T J)^-1.
void FusedUncertainty(const Problem& p, const Eigen::Matrix2d& h_equations,
                      const Eigen::Matrix2d& h_prior, bool solve_theta, DistanceEstimate* out) {
  Eigen::Matrix2d h = h_equations + h_prior;
  const GeometricModel& geo = p.model->geometric;
  const double noise = p.frame_noise_rel > 0.0 ? p.frame_noise_rel : geo.NoiseRel(out->d_mm);
  if (noise > 0.0 && geo.summary.mean_relative_error > 0.0) {
    const double scale = geo.summary.mean_relative_error / noise;
    h = scale * scale * h_equations + h_prior;
  }
  if (solve_theta && h.determinant() > 0.0) {
    const Eigen::Matrix2d cov = h.inverse();
    out->d_std_mm = out->d_mm * std::sqrt(cov(0, 0));
    out->theta_std_deg = std::sqrt(cov(1, 1)) / kRad;
  } else if (h(0, 0) > 0.0) {
    out->d_std_mm = out->d_mm / std::sqrt(h(0, 0));
  }
}

// Condition number and (kFused) uncertainties from the Jacobian at the solution.
void ReportConditioning(const Problem& p, const double x[2], bool solve_theta,
                        DistanceEstimate* out) {
  Eigen::Matrix2d h_equations, h_prior;
  NormalMatrices(p, x, &h_equations, &h_prior);
  if (solve_theta) {
    const Eigen::Vector2d ev =
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(h_equations + h_prior).eigenvalues();
    out->condition_number =
        ev(0) > 0.0 ? std::sqrt(ev(1) / ev(0)) : std::numeric_limits<double>::infinity();
  } else {
    out->condition_number = 1.0;
  }
  if (p.fused) FusedUncertainty(p, h_equations, h_prior, solve_theta, out);
}

constexpr double kRangeZ = 3.0;  // RangeOptions::z_limit's default (bracket_checks.h)

// Distance, and theta when solved, each edge widened by 3 standard errors of the estimate.
bool OutsideCalibratedRange(const CalibratedRanges& cr, const DistanceEstimate& e,
                            bool solve_theta) {
  return cr.DistanceOutside(e.d_mm, e.d_std_mm, kRangeZ) ||
         (solve_theta && cr.ThetaOutside(e.theta_deg, e.theta_std_deg, kRangeZ));
}

// Eq. 26 by ceres::TinySolver on 2 (or 1, theta fixed) unknowns, from out->d0_mm, theta0_deg.
void SolveLm(const Problem& p, bool solve_theta, const EstimateOptions& options,
             DistanceEstimate* out) {
  double x[2] = {std::log(out->d0_mm), out->theta0_deg * kRad};
  out->converged = solve_theta ? RunTinySolver<2>(p, options, x, &out->iterations)
                               : RunTinySolver<1>(p, options, x, &out->iterations);
  out->d_mm = std::exp(x[0]);
  out->theta_deg = std::abs(x[1]) / kRad;  // rho is even: the sign is not observable
  out->theta_solved = solve_theta;
  ReportPlainResiduals(p, x, out);
  ReportConditioning(p, x, solve_theta, out);
  out->outside_calibrated_range = OutsideCalibratedRange(p.model->ranges, *out, solve_theta);
}

// Sum of |relative residual| of the voting equations at scaled D, theta0, over all differences.
double Vote(const Problem& p, double scaled_d, double theta0_deg) {
  const double d_mm = p.model->scaling.DistanceFromScaledD(scaled_d);
  double r[kMaxResiduals];
  const int n = Residuals(p, std::log(d_mm), theta0_deg * kRad, r);
  double s = 0.0;
  for (int i = 0; i < n; ++i) s += std::abs(r[i]);
  return std::isfinite(s) ? s : std::numeric_limits<double>::infinity();
}

// RootTieBreaker::kGeometric: the mean of the frames' geometric ln d (NaN when there is none, or
// under the other tie-breaker).
double TieBreakingLnD(const Problem& p, const EstimateOptions& options) {
  if (options.tie_breaker != RootTieBreaker::kGeometric || p.geo_ln_d == nullptr) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  double sum = 0.0;
  int count = 0;
  for (int i = 0; i < p.count; ++i) {
    if (std::isfinite(p.geo_ln_d[i])) {
      sum += p.geo_ln_d[i];
      ++count;
    }
  }
  return count > 0 ? sum / count : std::numeric_limits<double>::quiet_NaN();
}

// Root selection: real, positive D, inside the calibrated range, smallest residual in the
// equations that vote (Eq. 25 first, then each equation alone, then mid-range).
void ChooseStart(const Problem& p, double theta0_deg, const EstimateOptions& options,
                 DistanceEstimate* out) {
  const ModelScaling& sc = p.model->scaling;
  const CalibratedRanges& cr = p.model->ranges;
  const double d_lo = cr.d_min_mm / (1.0 + options.range_margin);
  const double d_hi = cr.d_max_mm * (1.0 + options.range_margin);
  const double tie_geo_ln_d = TieBreakingLnD(p, options);
  // Polynomials in scaled D from the first difference (Eq. 21, 23), each normalised to unit norm.
  const Difference& df = p.diffs[0];
  double vars[kNumModelVars] = {0.0, 0.0, 0.0, 0.0, df.dt, df.df};
  double a[4], c[4];
  vars[kVarRho] = Rho(theta0_deg, p.s->sigma_deg);
  AlgebraicPolynomialInD(GetModelSpec(ModelKind::kFreeSigma), p.s->coefficients.data(), vars, df.ds,
                         c);
  NormaliseToUnitNorm(c);
  vars[kVarRho] = Rho(theta0_deg, p.e->sigma_deg);
  AlgebraicPolynomialInD(GetModelSpec(ModelKind::kFreeE), p.e->coefficients.data(), vars, df.de, a);
  NormaliseToUnitNorm(a);

  auto try_poly = [&](const double poly[4], RootSource source, bool count) {
    double roots[3];
    const int n = RealRoots(poly, roots);
    double best = std::numeric_limits<double>::infinity();
    int in_range = 0;
    for (int i = 0; i < n; ++i) {
      if (!(roots[i] > 0.0)) continue;
      const double d_mm = sc.DistanceFromScaledD(roots[i]);
      if (d_mm < d_lo || d_mm > d_hi) continue;
      ++in_range;
      const double v = p.geo_ln_d != nullptr && tie_geo_ln_d == tie_geo_ln_d
                           ? std::abs(std::log(d_mm) - tie_geo_ln_d)
                           : Vote(p, roots[i], theta0_deg);
      if (v < best) {
        best = v;
        out->d0_mm = d_mm;
        out->root_index = i;
        out->root_source = source;
      }
    }
    if (count) {
      out->num_real_roots = n;
      out->num_roots_in_range = in_range;
    }
    return in_range > 0;
  };

  if (!p.use_e) {
    if (try_poly(c, RootSource::kSigmaOnly, true)) return;
  } else {
    double diff[4];
    for (int k = 0; k < 4; ++k) diff[k] = c[k] - a[k];  // Eq. 25
    if (try_poly(diff, RootSource::kCubic, true)) return;
    if (try_poly(c, RootSource::kSingleModel, false)) return;
    if (try_poly(a, RootSource::kSingleModel, false)) return;
  }
  out->root_source = RootSource::kFallback;
  out->root_index = -1;
  out->d0_mm = 0.5 * (cr.d_min_mm + cr.d_max_mm);
}

void Prepare(const CalibrationModel& model, const FittedModel** e, const FittedModel** s) {
  *e = model.Find(ModelKind::kFreeE);
  *s = model.Find(ModelKind::kFreeSigma);
  IRDIST_CHECK(*s != nullptr && !(*s)->coefficients.empty(),
               "the model has no fitted free_sigma (Eq. 18) model");
  IRDIST_CHECK(*e != nullptr && !(*e)->coefficients.empty(),
               "the model has no fitted free_e (Eq. 17) model");
}

Difference MakeDifference(const ModelScaling& sc, const Features& ref, double t_ref_ms,
                          const Features& meas, double t_ms) {
  return Difference{(t_ms - t_ref_ms) / sc.t_scale_ms, (meas.f00 - ref.f00) / sc.df_scale,
                    meas.e_rel - ref.e_rel, meas.sigma - ref.sigma};
}

DistanceEstimate Solve(const Problem& p, double theta0_deg, const EstimateOptions& options) {
  DistanceEstimate out;
  out.theta0_deg = theta0_deg;
  ChooseStart(p, theta0_deg, options, &out);
  SolveLm(p, p.use_e, options, &out);
  return out;
}

ThetaStartOptions ThetaStartOf(const EstimateOptions& options) {
  ThetaStartOptions t;
  t.from_features = options.theta_source == ThetaSource::kFeatures;
  t.bracket_moments = options.theta_source == ThetaSource::kBracketMoments;
  t.correction = options.theta_correction;
  return t;
}

// ln of the frame's geometric distance, NaN when there is none.
double GeometricLnD(const CalibrationModel& model, const Features& f) {
  if (!model.geometric.fitted() || !f.blob_found) return std::numeric_limits<double>::quiet_NaN();
  const double d_mm = model.geometric.DistanceMm(model.geometric.FrameMajorVarPx2(f));
  return std::isfinite(d_mm) ? std::log(d_mm) : std::numeric_limits<double>::quiet_NaN();
}

// The rms over `frames` of each frame's noise of ln d: its blob-fit major-axis variance's
// standard error through the geometric model's slope. 0 when a frame has none (the moments'
// path, no model).
double FrameNoiseRel(const CalibrationModel& model, const Features* const* frames, int n) {
  const GeometricModel& g = model.geometric;
  double sum = 0.0;
  for (int i = 0; i < n; ++i) {
    const Features& f = *frames[i];
    const double var = g.FrameMajorVarPx2(f);
    const double se = f.major_var_se_px2;
    if (!g.fitted() || !(se > 0.0) || !(var > se)) return 0.0;
    const double noise = g.DistanceSeMm(var, se) / g.DistanceMm(var);
    if (!std::isfinite(noise) || !(noise > 0.0)) return 0.0;
    sum += noise * noise;
  }
  return n > 0 ? std::sqrt(sum / n) : 0.0;
}

// Weight of an equation: 1 / its calibration fit's mean relative error (floored).
double FitWeight(const FitSummary& s) {
  return 1.0 / std::max(s.mean_relative_error > 0.0 ? s.mean_relative_error : 1.0, 1e-6);
}

void SetUpFused(const CalibrationModel& model, const EstimateOptions& options, const double* geo,
                double theta_prior_deg, Problem* p) {
  p->geo_ln_d = geo;
  if (options.method != EstimateMethod::kFused) return;
  p->fused = true;
  p->e_weight = FitWeight(p->e->summary) * options.radiometric_weight;
  // A failed Sigma fit (e.g. one with a pole inside the calibrated range, model_poles.h) is no
  // equation: the distance rests on the geometric ones.
  p->s_weight = p->s->summary.termination == FitSummary::Termination::kFailed
                    ? 0.0
                    : FitWeight(p->s->summary) * options.radiometric_weight;
  p->huber = options.radiometric_huber;
  // Geometric summary residuals are relative distance errors: the weight is for ln d directly.
  if (model.geometric.fitted()) {
    p->geo_weight = FitWeight(model.geometric.summary) * options.geometric_weight;
  }
  p->theta_prior_rad = theta_prior_deg * kRad;
  p->theta_prior_weight = 1.0 / (options.theta_prior_sd_deg * kRad);
}

// EstimateOptions::reference_size: the reference frame's size as one more geometric equation,
// weighted by the reference's share of the light against the mean measurement exposure.
void SetUpReferenceSize(const CalibrationModel& model, const EstimateOptions& options,
                        const Features& reference, double t_ref_ms, const double* t_ms, int n,
                        Problem* p) {
  if (!options.reference_size || !(p->geo_weight > 0.0)) return;
  double mean_t_ms = 0.0;
  for (int i = 0; i < n; ++i) mean_t_ms += t_ms[i] / n;
  if (!(t_ref_ms > 0.0) || !(mean_t_ms > 0.0)) return;
  p->ref_geo_ln_d = GeometricLnD(model, reference);
  p->ref_geo_weight = p->geo_weight * std::sqrt(t_ref_ms / mean_t_ms);
}

double MeanFinite(const double* v, int n) {
  double sum = 0.0;
  int count = 0;
  for (int i = 0; i < n; ++i) {
    if (std::isfinite(v[i])) {
      sum += v[i];
      ++count;
    }
  }
  return count > 0 ? std::exp(sum / count) : 0.0;
}

}  // namespace

const char* ToString(RootSource source) {
  switch (source) {
    case RootSource::kCubic:
      return "eq25_cubic";
    case RootSource::kSigmaOnly:
      return "sigma_only";
    case RootSource::kSingleModel:
      return "single_model";
    case RootSource::kFallback:
      return "fallback_mid_range";
  }
  return "unknown";
}

std::string DistanceEstimate::BriefReport() const {
  std::ostringstream out;
  out << "d = " << d_mm << " mm, theta = " << theta_deg << " deg"
      << (theta_solved ? "" : " (theta from the ellipse)") << "; start d0 = " << d0_mm << " mm ("
      << ToString(root_source) << ", root " << root_index << " of " << num_real_roots << ", "
      << num_roots_in_range << " in range), theta0 = " << theta0_deg << " deg; residuals E "
      << residual_e << " S " << residual_sigma << ", " << iterations << " iterations, cond "
      << condition_number << (converged ? "" : ", NOT CONVERGED")
      << (outside_calibrated_range ? ", OUTSIDE CALIBRATED RANGE" : "");
  return out.str();
}

std::string BracketEstimate::BriefReport() const {
  std::ostringstream out;
  out << "joint: " << joint.BriefReport();
  for (size_t i = 0; i < per_exposure.size(); ++i) {
    out << "\n  exposure " << i << ": " << per_exposure[i].BriefReport();
  }
  return out.str();
}

DistanceEstimate EstimatePair(const CalibrationModel& model, const Features& reference_frame,
                              double t_ref_ms, const Features& measurement_frame, double t_ms,
                              const EstimateOptions& options) {
  Features reference = reference_frame, measurement = measurement_frame;
  PoolRoundBlobRule({&reference, &measurement});
  const FittedModel *e, *s;
  Prepare(model, &e, &s);
  const Difference diff = MakeDifference(model.scaling, reference, t_ref_ms, measurement, t_ms);
  const double geo = GeometricLnD(model, measurement);
  const Features* pair[2] = {&reference, &measurement};
  const double theta0 = Theta0Combined(model, pair, 2, measurement, ThetaStartOf(options));
  Problem p{&model, e, s, !e->degenerate, &diff, 1};
  SetUpFused(model, options, &geo, theta0, &p);
  SetUpReferenceSize(model, options, reference, t_ref_ms, &t_ms, 1, &p);
  p.frame_noise_rel = FrameNoiseRel(model, &pair[1], 1);
  DistanceEstimate out = Solve(p, theta0, options);
  out.d_geometric_mm = MeanFinite(&geo, 1);
  return out;
}

BracketEstimate EstimateBracket(const CalibrationModel& model, const Features& reference_frame,
                                double t_ref_ms, const std::vector<Features>& measurement_frames,
                                const std::vector<double>& t_ms, const EstimateOptions& options) {
  std::string why;
  IRDIST_CHECK(options.IsValid(&why), why);
  IRDIST_CHECK(measurement_frames.size() == t_ms.size(), "measurements and t_ms differ in length");
  IRDIST_CHECK(!t_ms.empty() && t_ms.size() <= kMaxBracketExposures, "a bracket needs 1..",
               kMaxBracketExposures, " measurement frames");
  Features reference = reference_frame;
  std::vector<Features> measurements = measurement_frames;
  PoolBracket(&reference, &measurements);
  const FittedModel *e, *s;
  Prepare(model, &e, &s);
  BracketEstimate out;
  Difference diffs[kMaxBracketExposures];
  double geo[kMaxBracketExposures];
  double thetas[kMaxBracketExposures];
  const int n = static_cast<int>(measurements.size());
  double theta0 = 0.0;
  for (int i = 0; i < n; ++i) {
    diffs[i] = MakeDifference(model.scaling, reference, t_ref_ms, measurements[i], t_ms[i]);
    geo[i] = GeometricLnD(model, measurements[i]);
    const Features* pair[2] = {&reference, &measurements[i]};
    thetas[i] = Theta0Combined(model, pair, 2, measurements[i], ThetaStartOf(options));
    theta0 += thetas[i] / n;
  }
  if (options.theta_source == ThetaSource::kBracketMoments) {
    const Features* frames[kMaxBracketExposures + 1];
    frames[0] = &reference;
    for (int i = 0; i < n; ++i) frames[i + 1] = &measurements[i];
    theta0 = Theta0Combined(model, frames, n + 1, measurements[0], ThetaStartOf(options));
  }
  for (int i = 0; i < n; ++i) {
    Problem p{&model, e, s, !e->degenerate, &diffs[i], 1};
    SetUpFused(model, options, &geo[i], thetas[i], &p);
    SetUpReferenceSize(model, options, reference, t_ref_ms, &t_ms[i], 1, &p);
    const Features* frame = &measurements[i];
    p.frame_noise_rel = FrameNoiseRel(model, &frame, 1);
    out.per_exposure.push_back(Solve(p, thetas[i], options));
    out.per_exposure.back().d_geometric_mm = MeanFinite(&geo[i], 1);
  }
  // Jointly: start from the per-exposure estimate with the smallest residuals.
  Problem joint{&model, e, s, !e->degenerate, diffs, n};
  SetUpFused(model, options, geo, theta0, &joint);
  SetUpReferenceSize(model, options, reference, t_ref_ms, t_ms.data(), n, &joint);
  const Features* frames[kMaxBracketExposures];
  for (int i = 0; i < n; ++i) frames[i] = &measurements[i];
  joint.frame_noise_rel = FrameNoiseRel(model, frames, n);
  const DistanceEstimate* best = &out.per_exposure[0];
  for (const DistanceEstimate& d : out.per_exposure) {
    if (d.residual_e + d.residual_sigma < best->residual_e + best->residual_sigma) best = &d;
  }
  out.joint = *best;
  out.joint.theta0_deg = theta0;
  if (!e->degenerate) out.joint.theta0_deg = best->theta_deg;
  out.joint.d0_mm = best->d_mm;
  out.joint.d_geometric_mm = MeanFinite(geo, n);
  SolveLm(joint, !e->degenerate, options, &out.joint);
  return out;
}

}  // namespace irdist
