#include "estimator/fit.h"

#include <ceres/ceres.h>

#include <boost/math/tools/minima.hpp>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <tuple>

#include "base/check.h"
#include "estimator/fit_status.h"

namespace irdist {
namespace {

// One observation of one model: scaled variables (rho filled from theta), target y.
struct Observation {
  std::array<double, kNumModelVars> vars;
  double theta_deg;
  double y;
};

bool UsesDirect(ModelKind k) {
  return k == ModelKind::kDirectE || k == ModelKind::kDirectF || k == ModelKind::kDirectSigma;
}
bool UsesDiff(ModelKind k) {
  return k == ModelKind::kDiffE || k == ModelKind::kDiffF || k == ModelKind::kDiffSigma;
}

double Target(ModelKind k, const Features& f) {
  switch (k) {
    case ModelKind::kDirectE:
    case ModelKind::kDiffE:
    case ModelKind::kFreeE:
      return f.e_rel;
    case ModelKind::kDirectF:
    case ModelKind::kDiffF:
      return f.f00;
    case ModelKind::kDirectSigma:
    case ModelKind::kDiffSigma:
    case ModelKind::kFreeSigma:
      return f.sigma;
  }
  return 0.0;
}

bool SampleUsable(const CalibrationSample& s, const FitOptions& options) {
  return !options.skip_flagged_samples || (s.reference.Usable() && s.measurement.Usable());
}

std::vector<Observation> MakeObservations(ModelKind kind,
                                          const std::vector<CalibrationSample>& samples,
                                          const ModelScaling& scaling, const FitOptions& options) {
  std::vector<Observation> out;
  std::set<std::tuple<double, double, double, double>> seen_references;
  for (const CalibrationSample& s : samples) {
    if (!SampleUsable(s, options)) continue;
    ModelInputs in;
    in.d_mm = s.d_mm;
    in.theta_deg = s.theta_deg;
    in.bias_ma = s.bias_ma;
    if (UsesDirect(kind)) {
      // Each frame once: references are shared by the measurement frames of a bracket.
      if (seen_references.insert({s.d_mm, s.theta_deg, s.bias_ma, s.t_ref_ms}).second) {
        in.t_ms = s.t_ref_ms;
        out.push_back({ScaleInputs(in, scaling), s.theta_deg, Target(kind, s.reference)});
      }
      in.t_ms = s.t_ms;
      out.push_back({ScaleInputs(in, scaling), s.theta_deg, Target(kind, s.measurement)});
    } else {
      in.dt_ms = s.t_ms - s.t_ref_ms;
      in.df = s.measurement.f00 - s.reference.f00;
      const double y = Target(kind, s.measurement) - Target(kind, s.reference);
      out.push_back({ScaleInputs(in, scaling), s.theta_deg, y});
    }
  }
  return out;
}

struct RelativeResidual {
  const ModelSpec* spec;
  Observation obs;
  template <typename T>
  bool operator()(T const* const* parameters, T* residual) const {
    T vars[kNumModelVars];
    for (int v = 0; v < kNumModelVars; ++v) vars[v] = T(obs.vars[v]);
    vars[kVarRho] = Rho(T(obs.theta_deg), parameters[1][0]);
    residual[0] = EvaluateModel(*spec, parameters[0], vars) / obs.y - 1.0;
    return true;
  }
};

double RelativeCost(const ModelSpec& spec, const std::vector<double>& c, double sigma,
                    const std::vector<Observation>& obs, std::vector<double>* residuals) {
  double cost = 0.0;
  if (residuals) residuals->resize(obs.size());
  for (size_t i = 0; i < obs.size(); ++i) {
    std::array<double, kNumModelVars> v = obs[i].vars;
    v[kVarRho] = Rho(obs[i].theta_deg, sigma);
    const double r = EvaluateModel(spec, c.data(), v.data()) / obs[i].y - 1.0;
    if (residuals) (*residuals)[i] = r;
    cost += std::isfinite(r) ? r * r : 1e300;
  }
  return cost;
}

// Linear start for a fixed sigma: relative least squares (no denominator), or for the ratio models
// the smallest right singular vector of the algebraic residual (Num - y Den) / (y Den_prev),
// reweighted a few times by the previous denominator (Sanathanan-Koerner) so that it approaches
// the relative residual the LM minimises.
std::vector<double> LinearStart(const ModelSpec& spec, const std::vector<int>& active, double sigma,
                                const std::vector<Observation>& obs) {
  const int n = static_cast<int>(active.size());
  Eigen::MatrixXd m(obs.size(), n);  // monomials
  for (size_t i = 0; i < obs.size(); ++i) {
    std::array<double, kNumModelVars> v = obs[i].vars;
    v[kVarRho] = Rho(obs[i].theta_deg, sigma);
    double powers[kNumModelVars][4];
    PowerTable(v.data(), powers);
    for (int c = 0; c < n; ++c) m(i, c) = MonomialValue(spec.terms[active[c]], powers);
  }
  std::vector<double> coefficients(spec.num_coefficients(), 0.0);
  Eigen::VectorXd weight = Eigen::VectorXd::Ones(obs.size());
  const int rounds = spec.has_denominator() ? 4 : 1;
  for (int round = 0; round < rounds; ++round) {
    Eigen::MatrixXd a(obs.size(), n);
    for (size_t i = 0; i < obs.size(); ++i) {
      for (int c = 0; c < n; ++c) {
        a(i, c) = (active[c] < spec.num_numerator ? m(i, c) / obs[i].y : -m(i, c)) * weight(i);
      }
    }
    Eigen::VectorXd norms = a.colwise().norm();
    for (int c = 0; c < n; ++c) {
      if (norms(c) <= 0.0) norms(c) = 1.0;
      a.col(c) /= norms(c);
    }
    Eigen::VectorXd x;
    if (spec.has_denominator()) {
      Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeThinV);
      x = svd.matrixV().col(n - 1);
    } else {
      x = a.colPivHouseholderQr().solve(Eigen::VectorXd::Ones(obs.size()));
    }
    for (int c = 0; c < n; ++c) coefficients[active[c]] = x(c) / norms(c);
    if (!spec.has_denominator()) break;
    for (size_t i = 0; i < obs.size(); ++i) {
      double den = 0.0;
      for (int c = 0; c < n; ++c) {
        if (active[c] >= spec.num_numerator) den += coefficients[active[c]] * m(i, c);
      }
      weight(i) = std::abs(den) > 0.0 ? 1.0 / std::abs(den) : 1.0;
    }
    weight /= weight.maxCoeff();
  }
  return coefficients;
}

// The fit's condition number, and a converged fit that is degenerate or ill-conditioned said so.
void ApplyConditioning(const FitConditioning& c, FitSummary* summary) {
  summary->condition_number = c.condition_number;
  if (summary->termination != FitSummary::Termination::kConverged || c.Note().empty()) return;
  summary->termination = c.degenerate() ? FitSummary::Termination::kDegenerate
                                        : FitSummary::Termination::kIllConditioned;
  summary->message += (summary->message.empty() ? "" : "; ") + c.Note();
}

// Whether dE (or E_rel) is proportional to dF (F) over the samples: the E equation is then F's.
bool EProportionalToF(ModelKind kind, const std::vector<CalibrationSample>& samples,
                      const ModelScaling& scaling, const FitOptions& options) {
  const ModelKind f_kind = UsesDirect(kind) ? ModelKind::kDirectF
                           : UsesDiff(kind) ? ModelKind::kDiffF
                                            : ModelKind::kDiffF;
  const std::vector<Observation> e = MakeObservations(kind, samples, scaling, options);
  const std::vector<Observation> f = MakeObservations(f_kind, samples, scaling, options);
  if (e.empty() || e.size() != f.size()) return false;
  double mean_ratio = 0.0;
  for (size_t i = 0; i < e.size(); ++i) mean_ratio += e[i].y / f[i].y;
  mean_ratio /= e.size();
  for (size_t i = 0; i < e.size(); ++i) {
    if (std::abs(e[i].y / (mean_ratio * f[i].y) - 1.0) > options.degenerate_tolerance) return false;
  }
  return true;
}

void FillErrors(FitSummary* s) {
  double sum = 0.0, worst = 0.0;
  for (double r : s->residuals) {
    sum += std::abs(r);
    worst = std::max(worst, std::abs(r));
  }
  s->mean_relative_error = s->residuals.empty() ? -1.0 : sum / s->residuals.size();
  s->max_relative_error = s->residuals.empty() ? -1.0 : worst;
}

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

FitOptions PaperFitOptions() {
  FitOptions options;
  options.free_form = ModelForm::kFull;
  return options;
}

bool FitOptions::IsValid(std::string* why) const {
  auto fail = [why](const char* text) {
    if (why) *why = text;
    return false;
  };
  if (models.empty()) return fail("models: nothing to fit");
  if (!(sigma_min_deg > 0.0 && sigma_max_deg > sigma_min_deg))
    return fail("need 0 < sigma_min_deg < sigma_max_deg");
  if (sigma_scan_steps < 2) return fail("sigma_scan_steps must be >= 2");
  if (multi_starts < 1 || multi_starts > sigma_scan_steps)
    return fail("multi_starts must be in [1, sigma_scan_steps]");
  if (max_iterations < 1) return fail("max_iterations must be >= 1");
  if (!(function_tolerance >= 0.0 && gradient_tolerance >= 0.0 && parameter_tolerance >= 0.0))
    return fail("tolerances must be >= 0");
  if (!(degenerate_tolerance > 0.0)) return fail("degenerate_tolerance must be > 0");
  if (theta_correction_degree < 1 || theta_correction_degree > 3)
    return fail("theta_correction_degree must be in [1, 3]");
  return true;
}

const char* ToString(FitSummary::Termination termination) {
  switch (termination) {
    case FitSummary::Termination::kConverged:
      return "converged";
    case FitSummary::Termination::kNoConvergence:
      return "no_convergence";
    case FitSummary::Termination::kFailed:
      return "failed";
    case FitSummary::Termination::kDegenerate:
      return "degenerate";
    case FitSummary::Termination::kIllConditioned:
      return "ill-conditioned";
  }
  return "unknown";
}

std::string FitSummary::BriefReport() const {
  std::ostringstream out;
  out << ToString(termination) << ": " << samples << " samples, mean relative error "
      << 100.0 * mean_relative_error << "%, max " << 100.0 * max_relative_error
      << "%, condition number " << condition_number << ", " << iterations << " iterations";
  if (!message.empty()) out << " (" << message << ")";
  return out.str();
}

const FittedModel* CalibrationModel::Find(ModelKind kind) const {
  for (const FittedModel& m : models) {
    if (m.kind == kind) return &m;
  }
  return nullptr;
}

std::string CalibrationModel::BriefReport() const {
  std::ostringstream out;
  out << "calibration: d " << ranges.d_min_mm << ".." << ranges.d_max_mm << " mm, theta "
      << ranges.theta_min_deg << ".." << ranges.theta_max_deg << " deg, ROI "
      << ToString(features.roi_policy) << "\n";
  for (const FittedModel& m : models) {
    out << "  " << ToString(m.kind) << " (" << ToString(m.form) << ", sigma " << m.sigma_deg
        << " deg" << (m.degenerate ? ", DEGENERATE" : "") << "): " << m.summary.BriefReport()
        << "\n";
  }
  if (geometric.fitted()) out << "  geometric: " << geometric.summary.BriefReport() << "\n";
  if (theta_correction.fitted()) {
    out << "  theta correction (degree " << theta_correction.degree << "): "
        << theta_correction.summary.samples << " frames, mean |error| "
        << theta_correction.summary.mean_relative_error << " deg, max "
        << theta_correction.summary.max_relative_error << " deg\n";
  }
  return out.str();
}

ModelScaling ChooseScaling(const std::vector<CalibrationSample>& samples) {
  ModelScaling s;
  IRDIST_CHECK(!samples.empty(), "no calibration samples");
  double sum_d = 0.0, sum_dt = 0.0, sum_i = 0.0, sum_df = 0.0;
  for (const CalibrationSample& x : samples) {
    IRDIST_CHECK(x.d_mm > 0.0, "sample with d_mm <= 0");
    const double r = s.d_ref_mm / x.d_mm;
    sum_d += r * r;
    sum_dt += std::abs(x.t_ms - x.t_ref_ms);
    sum_i += std::abs(x.bias_ma);
    sum_df += std::abs(x.measurement.f00 - x.reference.f00);
  }
  const double n = samples.size();
  auto positive = [](double v) { return v > 0.0 && std::isfinite(v) ? v : 1.0; };
  s.d_scale = positive(sum_d / n);
  s.t_scale_ms = positive(sum_dt / n);
  s.i0_scale_ma = positive(sum_i / n);
  s.df_scale = positive(sum_df / n);
  return s;
}

namespace {

// A linear start of the LM: its relative cost, sigma (deg) and coefficients.
struct Start {
  double cost;
  double sigma;
  std::vector<double> c;
};

// What FitModel fits: the observations of one model in one form, its active terms, and whether
// sigma is free (the calibration spans more than one theta).
struct FitInput {
  const ModelSpec* spec;
  ModelForm form;
  std::vector<Observation> obs;
  std::vector<int> active;
  bool sigma_free;
};

FitInput MakeFitInput(ModelKind kind, ModelForm form, const std::vector<CalibrationSample>& samples,
                      const ModelScaling& scaling, const FitOptions& options) {
  FitInput in{&GetModelSpec(kind), form, MakeObservations(kind, samples, scaling, options), {},
              false};
  for (int j = 0; j < in.spec->num_coefficients(); ++j) {
    if (IsTermActive(*in.spec, form, j)) in.active.push_back(j);
  }
  IRDIST_CHECK(in.obs.size() > in.active.size(), ToString(kind), ": ", in.obs.size(),
               " usable observations for ", in.active.size() + 1, " unknowns");
  double theta_min = in.obs.front().theta_deg, theta_max = theta_min;
  for (const Observation& o : in.obs) {
    IRDIST_CHECK(o.y != 0.0 && std::isfinite(o.y), ToString(kind),
                 ": a target of 0 makes the relative residual undefined");
    theta_min = std::min(theta_min, o.theta_deg);
    theta_max = std::max(theta_max, o.theta_deg);
  }
  in.sigma_free = theta_max - theta_min > 1e-9;
  return in;
}

Start StartAt(const FitInput& in, double sigma) {
  std::vector<double> c = LinearStart(*in.spec, in.active, sigma, in.obs);
  const double cost = RelativeCost(*in.spec, c, sigma, in.obs, nullptr);
  return Start{cost, sigma, std::move(c)};
}

// Linear starts on the sigma scan (geometric steps), best first.
std::vector<Start> ScanStarts(const FitInput& in, const FitOptions& options) {
  std::vector<Start> starts;
  const int steps = in.sigma_free ? options.sigma_scan_steps : 1;
  for (int k = 0; k < steps; ++k) {
    const double sigma =
        steps == 1 ? options.sigma_max_deg
                   : options.sigma_min_deg *
                         std::pow(options.sigma_max_deg / options.sigma_min_deg, k / (steps - 1.0));
    starts.push_back(StartAt(in, sigma));
  }
  std::sort(starts.begin(), starts.end(),
            [](const Start& a, const Start& b) { return a.cost < b.cost; });
  return starts;
}

// The minimum in ln sigma of the linear start's cost between the best scan sigma's neighbours,
// by Brent's method (boost::math::tools::brent_find_minima) to half the double's bits: the LM
// then starts next to the minimum.
Start RefineScanSigma(const FitInput& in, const FitOptions& options, double best_sigma) {
  const double ratio = std::pow(options.sigma_max_deg / options.sigma_min_deg,
                                1.0 / (options.sigma_scan_steps - 1.0));
  auto cost_at = [&in](double log_sigma) {
    const double sigma = std::exp(log_sigma);
    return RelativeCost(*in.spec, LinearStart(*in.spec, in.active, sigma, in.obs), sigma, in.obs,
                        nullptr);
  };
  std::uintmax_t max_iterations = 100;
  const std::pair<double, double> minimum = boost::math::tools::brent_find_minima(
      cost_at, std::log(best_sigma / ratio), std::log(best_sigma * ratio),
      std::numeric_limits<double>::digits / 2, max_iterations);
  return StartAt(in, std::exp(minimum.first));
}

// Ratio models: divides c by its largest active denominator coefficient, which the LM then holds
// at 1 (the gauge). Returns its index, -1 without a denominator, -2 when no active one is nonzero.
int FixGauge(const ModelSpec& spec, ModelForm form, std::vector<double>* c) {
  if (!spec.has_denominator()) return -1;
  int gauge = -2;
  double biggest = 0.0;
  for (int j = spec.num_numerator; j < spec.num_coefficients(); ++j) {
    if (IsTermActive(spec, form, j) && std::abs((*c)[j]) > biggest) {
      biggest = std::abs((*c)[j]);
      gauge = j;
    }
  }
  if (gauge < 0) return gauge;
  const double g = (*c)[gauge];
  for (double& v : *c) v /= g;
  return gauge;
}

// The relative-residual problem on (c, sigma): the gauge and inactive terms held, sigma bounded
// (or held when the calibration has one theta only).
void BuildFitProblem(const FitInput& in, const FitOptions& options, int gauge,
                     std::vector<double>* c, double* sigma, ceres::Problem* problem) {
  const ModelSpec& spec = *in.spec;
  for (const Observation& o : in.obs) {
    auto* cost = new ceres::DynamicAutoDiffCostFunction<RelativeResidual, 8>(
        new RelativeResidual{&spec, o});
    cost->AddParameterBlock(spec.num_coefficients());
    cost->AddParameterBlock(1);
    cost->SetNumResiduals(1);
    problem->AddResidualBlock(cost, nullptr, c->data(), sigma);
  }
  std::vector<int> constant;
  for (int j = 0; j < spec.num_coefficients(); ++j) {
    if (j == gauge || !IsTermActive(spec, in.form, j)) constant.push_back(j);
  }
  if (!constant.empty()) {
    problem->SetManifold(c->data(), new ceres::SubsetManifold(spec.num_coefficients(), constant));
  }
  if (in.sigma_free) {
    problem->SetParameterLowerBound(sigma, 0, 0.5);
    // Bounded above by the scan's end: where the model barely depends on sigma it would
    // otherwise drift for the whole iteration budget (no_convergence at 1000 iterations).
    problem->SetParameterUpperBound(sigma, 0, options.sigma_max_deg);
  } else {
    problem->SetParameterBlockConstant(sigma);
  }
}

ceres::Solver::Options FitSolverOptions(const FitOptions& options) {
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_QR;
  solver.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  solver.max_num_iterations = options.max_iterations;
  solver.function_tolerance = options.function_tolerance;
  solver.gradient_tolerance = options.gradient_tolerance;
  solver.parameter_tolerance = options.parameter_tolerance;
  solver.num_threads = 1;
  solver.logging_type = ceres::SILENT;
  return solver;
}

FitSummary::Termination TerminationOf(const ceres::Solver::Summary& summary) {
  return summary.termination_type == ceres::CONVERGENCE      ? FitSummary::Termination::kConverged
         : summary.termination_type == ceres::NO_CONVERGENCE ? FitSummary::Termination::kNoConvergence
                                                             : FitSummary::Termination::kFailed;
}

// The summary of a refined start (number `index` of `count`) except residuals and errors.
void SummariseRefinement(const FitInput& in, const FitOptions& options,
                         const ceres::Solver::Summary& summary, const Start& start, int index,
                         int count, FittedModel* model) {
  FitSummary& fs = model->summary;
  fs.termination = TerminationOf(summary);
  fs.message = "start " + std::to_string(index + 1) + " of " + std::to_string(count) +
               " from sigma " + std::to_string(start.sigma) + " deg";
  if (in.sigma_free && model->sigma_deg >= options.sigma_max_deg * (1.0 - 1e-6)) {
    // The I0-free ratios barely see the emission pattern (I0 rho cancels): sigma drifts along
    // a flat direction until the bound stops it. The fit error does not depend on it.
    fs.message += "; sigma at its upper bound (" + std::to_string(options.sigma_max_deg) +
                  " deg): the model barely depends on it";
  }
  fs.iterations = static_cast<int>(summary.iterations.size()) - 1;
  fs.samples = static_cast<int>(in.obs.size());
}

// LM (Ceres) from one start; replaces *best when its cost is lower than *best_cost.
void RefineStart(const FitInput& in, const FitOptions& options, const Start& start, int index,
                 int count, double* best_cost, FittedModel* best) {
  std::vector<double> c = start.c;
  double sigma = start.sigma;
  const int gauge = FixGauge(*in.spec, in.form, &c);
  if (gauge == -2) return;
  ceres::Problem problem;
  BuildFitProblem(in, options, gauge, &c, &sigma, &problem);
  ceres::Solver::Summary summary;
  ceres::Solve(FitSolverOptions(options), &problem, &summary);
  const double cost = RelativeCost(*in.spec, c, sigma, in.obs, nullptr);
  if (!(cost < *best_cost)) return;
  *best_cost = cost;
  best->coefficients = c;
  best->sigma_deg = sigma;
  SummariseRefinement(in, options, summary, start, index, count, best);
  best->summary.gauge_index = gauge;
  std::vector<double*> free_blocks{c.data()};
  if (in.sigma_free) free_blocks.push_back(&sigma);
  ApplyConditioning(
      ConditioningOf(&problem, free_blocks,
                     FreeParameterNames(*in.spec, in.form, gauge, in.sigma_free)),
      &best->summary);
}

}  // namespace

FittedModel FitModel(ModelKind kind, ModelForm form, const std::vector<CalibrationSample>& samples,
                     const ModelScaling& scaling, const FitOptions& options) {
  std::string why;
  IRDIST_CHECK(options.IsValid(&why), why);
  const FitInput in = MakeFitInput(kind, form, samples, scaling, options);
  FittedModel model;
  model.kind = kind;
  model.form = form;
  // 1. Linear starts on the sigma scan, the refined best first.
  std::vector<Start> starts = ScanStarts(in, options);
  if (in.sigma_free) starts.insert(starts.begin(), RefineScanSigma(in, options, starts[0].sigma));
  // 2. LM from the best starts.
  double best_cost = std::numeric_limits<double>::infinity();
  const int count = std::min<int>(options.multi_starts, starts.size());
  for (int s = 0; s < count; ++s) RefineStart(in, options, starts[s], s, count, &best_cost, &model);
  if (model.coefficients.empty()) {
    model.summary.message = "no start could be refined";
    return model;
  }
  RelativeCost(*in.spec, model.coefficients, model.sigma_deg, in.obs, &model.summary.residuals);
  FillErrors(&model.summary);
  if (kind == ModelKind::kDirectE || kind == ModelKind::kDiffE || kind == ModelKind::kFreeE) {
    model.degenerate = EProportionalToF(kind, samples, scaling, options);
    if (model.degenerate) model.summary.message += "; E proportional to F: degenerate";
  }
  return model;
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

// The measured blur of every usable measurement frame, at its true distance.
std::vector<BlurPoint> MeasuredBlur(const std::vector<CalibrationSample>& samples) {
  std::vector<BlurPoint> points;
  for (const CalibrationSample& s : samples) {
    if (!s.measurement.Usable() || !std::isfinite(s.measurement.blur_var_px2)) continue;
    points.push_back({s.d_mm, s.measurement.blur_var_px2});
  }
  return points;
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
  FillErrors(&g.summary);
  FitGeometricNoise(data.major_points, &g);
  g.summary.termination =
      g.alpha_px2 > 0.0 ? FitSummary::Termination::kConverged : FitSummary::Termination::kFailed;
  g.summary.message = blur_varies_with_distance
                          ? "linear least squares, blur quadratic in 1/d; residuals are relative "
                            "distance errors"
                          : "linear least squares; residuals are relative distance errors";
  return g;
}

namespace {

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
  FillErrors(&tc->summary);
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
