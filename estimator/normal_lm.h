#pragma once
// Levenberg-Marquardt on the normal equations, for the blob fit (estimator/blob_fit.cc;
// estimator-internal). The same steps as ceres::TinySolver (its Jacobi scaling from the first
// Jacobian's column norms, its damping and trust-region updates, its stopping rules), but the
// problem hands over J^T J and J^T r, not the residuals and the n x N Jacobian: the blob fit sums
// them per pixel as it computes the model, with no n x 7 matrix written and multiplied (the
// Jacobian's fill, scaling and product were a quarter of the fit's time), and a pixel far from the
// disc's edge adds to the amplitude and background terms only. Iterates equal TinySolver's up to
// the rounding of the sums' order (tests/estimator/normal_lm_test.cc).

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include <Eigen/Dense>

#include "base/check.h"

namespace irdist {

template <int N>
struct NormalEquations {
  double cost2 = 0.0;                    // sum of squared residuals, |r|^2
  Eigen::Matrix<double, N, N> jtj;       // J^T J (filled when asked for)
  Eigen::Matrix<double, N, 1> jtr;       // J^T r
};

// A problem: Evaluate(x, normal) sets normal->cost2, and with `want_normal` also jtj and jtr;
// returns false when the model cannot be evaluated at x.
template <int N>
class NormalProblem {
 public:
  virtual ~NormalProblem() = default;
  virtual bool Evaluate(const double* x, bool want_normal, NormalEquations<N>* normal) const = 0;
};

struct NormalLmOptions {
  int max_iterations = 50;          // TinySolver's defaults
  double gradient_tolerance = 1e-10;
  double parameter_tolerance = 1e-8;
  double function_tolerance = 1e-6;  // absolute, in |r|^2 / 2 units (as TinySolver uses it)
  double cost_threshold = 2.220446049250313e-16;
  double initial_trust_region_radius = 1e4;
  // Beyond TinySolver (0: off): stop at a point whose Gauss-Newton step would lower |r|^2 by less
  // than this (the Newton decrement g^T (J^T J)^-1 g, the full step's predicted decrease), without
  // evaluating that step. The solution then lies within sqrt(this) standard errors (Mahalanobis,
  // for unit-variance residuals) of the minimum: the guarantee function_tolerance's last accepted
  // step gives, one model evaluation sooner.
  double decrement_tolerance = 0.0;
  // Beyond TinySolver (0: off): at a point whose Newton decrement lies below this (and above
  // decrement_tolerance), take the Gauss-Newton step (undamped, the one the decrement measures)
  // and stop without evaluating the model there. The step is then less than sqrt(this) standard
  // errors, over which the model is linear far below its noise, so the point is the one an
  // evaluation would accept and stop at. The cost reported is the normal equations' prediction
  // (less half the decrement); the last evaluated point (where J^T J was computed, for a
  // covariance) goes to SolveNormalLm's `evaluated`.
  double final_step_decrement = 0.0;
  // The first problem, naming the field, in *why (empty when valid).
  bool IsValid(std::string* why) const {
    std::string reason;
    if (max_iterations < 1) reason = "max_iterations below 1";
    const double tolerances[] = {gradient_tolerance, parameter_tolerance, function_tolerance,
                                 cost_threshold, decrement_tolerance, final_step_decrement};
    const char* names[] = {"gradient_tolerance", "parameter_tolerance", "function_tolerance",
                           "cost_threshold", "decrement_tolerance", "final_step_decrement"};
    for (int i = 0; i < 6 && reason.empty(); ++i) {
      if (!(tolerances[i] >= 0.0) || !std::isfinite(tolerances[i])) {
        reason = std::string(names[i]) + " not a finite number >= 0";
      }
    }
    if (reason.empty() && !(initial_trust_region_radius > 0.0 &&
                            std::isfinite(initial_trust_region_radius))) {
      reason = "initial_trust_region_radius not a finite number > 0";
    }
    if (why != nullptr) *why = reason;
    return reason.empty();
  }
};

struct NormalLmSummary {
  double initial_cost = -1.0;  // |r|^2 / 2 at the start
  double final_cost = -1.0;    // the same at the solution
  int iterations = 0;
  int evaluations = 0;         // Evaluate calls
  bool decrement_stop = false; // stopped by decrement_tolerance
  bool final_step = false;      // stopped by final_step_decrement, the last step not evaluated
};

// The solver's state between its steps (SolveNormalLm below runs it).
template <int N>
class NormalLm {
 public:
  using Vector = Eigen::Matrix<double, N, 1>;
  using Matrix = Eigen::Matrix<double, N, N>;
  NormalLm(const NormalProblem<N>& problem, const NormalLmOptions& options)
      : problem_(problem), options_(options) {
    std::string why;
    IRDIST_CHECK(options.IsValid(&why), "NormalLmOptions: " + why);
  }

  // The last point the model was evaluated at (x unless the final step was taken unevaluated).
  const Vector& evaluated() const { return evaluated_; }

  NormalLmSummary Solve(Vector* x_inout) {
    Vector& x = *x_inout;
    evaluated_ = x;
    Update(x, true);
    summary_.initial_cost = summary_.final_cost = cost_;
    if (Converged()) return summary_;
    double u = 1.0 / options_.initial_trust_region_radius, v = 2.0;
    NormalEquations<N> trial;
    for (summary_.iterations = 1; summary_.iterations < options_.max_iterations;
         ++summary_.iterations) {
      if (options_.final_step_decrement > 0.0 && decrement_ < options_.final_step_decrement) {
        evaluated_ = x;
        x += scaling_.asDiagonal() * newton_step_;  // the Gauss-Newton step, undamped
        cost_ -= 0.5 * decrement_;                    // its predicted decrease of |r|^2 / 2
        summary_.final_step = true;
        break;
      }
      Matrix regularized = jtj_;
      for (int i = 0; i < N; ++i) {
        regularized(i, i) += u * std::min(std::max(jtj_(i, i), 1e-6), 1e32);
      }
      const Vector step = Eigen::LDLT<Matrix>(regularized).solve(g_);
      const Vector dx = scaling_.asDiagonal() * step;
      const double tolerance = options_.parameter_tolerance;
      if (dx.norm() < tolerance * (x.norm() + tolerance)) break;
      const Vector x_new = x + dx;
      ++summary_.evaluations;
      problem_.Evaluate(x_new.data(), false, &trial);
      const double cost_change = 2.0 * cost_ - trial.cost2;
      const double rho = cost_change / step.dot(2.0 * g_ - jtj_ * step);
      if (rho > 0.0) {
        x = x_new;
        if (std::abs(cost_change) < options_.function_tolerance) {
          cost_ = 0.5 * trial.cost2;
          break;
        }
        Update(x, false);
        if (Converged()) break;
        const double t = 2.0 * rho - 1.0;
        u *= std::max(1.0 / 3.0, 1.0 - t * t * t);
        v = 2.0;
      } else {
        if (std::abs(cost_change) < options_.function_tolerance) break;
        u *= v;
        v *= 2.0;
      }
    }
    if (!summary_.final_step) evaluated_ = x;
    summary_.final_cost = cost_;
    return summary_;
  }

 private:
  // TinySolver's Update: the scaled normal equations at x (the scaling fixed at the first).
  void Update(const Vector& x, bool first) {
    ++summary_.evaluations;
    if (!problem_.Evaluate(x.data(), true, &normal_)) return;
    if (first) scaling_ = (1.0 + normal_.jtj.diagonal().array().sqrt()).inverse().matrix();
    jtj_ = scaling_.asDiagonal() * normal_.jtj * scaling_.asDiagonal();
    g_ = -(scaling_.asDiagonal() * normal_.jtr);
    gradient_max_ = g_.array().abs().maxCoeff();
    cost_ = 0.5 * normal_.cost2;
  }
  // TinySolver's stops at a new point, and the Newton decrement below decrement_tolerance
  // (the scaling cancels in g^T (J^T J)^-1 g). Keeps the decrement and its Gauss-Newton step for
  // final_step_decrement (infinity when neither rule is on or the solve fails).
  bool Converged() {
    if (gradient_max_ < options_.gradient_tolerance || cost_ < options_.cost_threshold) return true;
    decrement_ = std::numeric_limits<double>::infinity();
    if (!(options_.decrement_tolerance > 0.0) && !(options_.final_step_decrement > 0.0)) {
      return false;
    }
    const Eigen::LDLT<Matrix> exact(jtj_);
    const Vector newton_step = exact.solve(g_);
    const double decrement = g_.dot(newton_step);
    if (exact.info() != Eigen::Success || !std::isfinite(decrement) || decrement < 0.0) {
      return false;
    }
    decrement_ = decrement;
    newton_step_ = newton_step;
    return summary_.decrement_stop = decrement < options_.decrement_tolerance;
  }

  const NormalProblem<N>& problem_;
  const NormalLmOptions options_;
  NormalLmSummary summary_;
  NormalEquations<N> normal_;
  Vector scaling_, g_, evaluated_;
  Vector newton_step_;  // the undamped Gauss-Newton step at the current point (scaled)
  Matrix jtj_;
  double cost_ = 0.0, gradient_max_ = 0.0;
  double decrement_ = std::numeric_limits<double>::infinity();  // at the current point
};

// Minimises |r(x)|^2 / 2 from *x in place; *evaluated (when given): the last point the model was
// evaluated at (options.final_step_decrement).
template <int N>
NormalLmSummary SolveNormalLm(const NormalProblem<N>& problem, const NormalLmOptions& options,
                              Eigen::Matrix<double, N, 1>* x_inout,
                              Eigen::Matrix<double, N, 1>* evaluated = nullptr) {
  NormalLm<N> solver(problem, options);
  const NormalLmSummary summary = solver.Solve(x_inout);
  if (evaluated != nullptr) *evaluated = solver.evaluated();
  return summary;
}

}  // namespace irdist
