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
#include "estimator/model_poles.h"

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

}  // namespace

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

void FitSummary::SetErrorsFromResiduals() {
  double sum = 0.0, worst = 0.0;
  for (double r : residuals) {
    sum += std::abs(r);
    worst = std::max(worst, std::abs(r));
  }
  mean_relative_error = residuals.empty() ? -1.0 : sum / residuals.size();
  max_relative_error = residuals.empty() ? -1.0 : worst;
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
  ModelScaling scaling;
};

FitInput MakeFitInput(ModelKind kind, ModelForm form, const std::vector<CalibrationSample>& samples,
                      const ModelScaling& scaling, const FitOptions& options) {
  FitInput in{&GetModelSpec(kind), form, MakeObservations(kind, samples, scaling, options), {},
              false, scaling};
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

// Where the ratio model c at sigma has a pole inside the calibrated domain (model_poles.h).
PoleScan PolesOf(const FitInput& in, const std::vector<double>& c, double sigma) {
  std::vector<std::array<double, kNumModelVars>> vars;
  std::vector<double> thetas;
  for (const Observation& o : in.obs) {
    vars.push_back(o.vars);
    thetas.push_back(o.theta_deg);
  }
  return ScanForPoles(*in.spec, c, sigma, vars, thetas, in.scaling.d_ref_mm, in.scaling.d_scale,
                      kDefaultRangeMargin);
}

// LM (Ceres) from one start; replaces *best when its cost is lower than *best_cost. A solution
// with a pole inside the calibrated domain never replaces one without (*best_has_pole says which
// *best is); the count of such solutions goes to *poles.
void RefineStart(const FitInput& in, const FitOptions& options, const Start& start, int index,
                 int count, double* best_cost, FittedModel* best, bool* best_has_pole,
                 int* poles) {
  std::vector<double> c = start.c;
  double sigma = start.sigma;
  const int gauge = FixGauge(*in.spec, in.form, &c);
  if (gauge == -2) return;
  ceres::Problem problem;
  BuildFitProblem(in, options, gauge, &c, &sigma, &problem);
  ceres::Solver::Summary summary;
  ceres::Solve(FitSolverOptions(options), &problem, &summary);
  const double cost = RelativeCost(*in.spec, c, sigma, in.obs, nullptr);
  const PoleScan pole = PolesOf(in, c, sigma);
  *poles += pole.pole ? 1 : 0;
  const bool better = best->coefficients.empty() || (*best_has_pole && !pole.pole) ||
                      (*best_has_pole == pole.pole && cost < *best_cost);
  if (!better) return;
  *best_cost = cost;
  *best_has_pole = pole.pole;
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
  if (pole.pole) {
    best->summary.termination = FitSummary::Termination::kFailed;
    best->summary.message += "; " + pole.Note() + ": every start has such a pole (a grid with "
                             "more distances and angles pins the ratio between them)";
  }
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
  bool best_has_pole = false;
  int poles = 0;
  const int count = std::min<int>(options.multi_starts, starts.size());
  for (int s = 0; s < count; ++s) {
    RefineStart(in, options, starts[s], s, count, &best_cost, &model, &best_has_pole, &poles);
  }
  if (model.coefficients.empty()) {
    model.summary.message = "no start could be refined";
    return model;
  }
  if (poles > 0 && !best_has_pole) {
    model.summary.message += "; " + std::to_string(poles) +
                             " solution(s) with a pole inside the calibrated range set aside";
  }
  RelativeCost(*in.spec, model.coefficients, model.sigma_deg, in.obs, &model.summary.residuals);
  model.summary.SetErrorsFromResiduals();
  if (kind == ModelKind::kDirectE || kind == ModelKind::kDiffE || kind == ModelKind::kFreeE) {
    model.degenerate = EProportionalToF(kind, samples, scaling, options);
    if (model.degenerate) model.summary.message += "; E proportional to F: degenerate";
  }
  return model;
}

}  // namespace irdist
