#include "estimator/normal_lm.h"

#include <gtest/gtest.h>

#include <ceres/tiny_solver.h>

#include <cmath>
#include <random>
#include <vector>

namespace irdist {
namespace {

// y = a exp(-b t) + c on noisy samples: the same problem as residuals (for ceres::TinySolver) and
// as normal equations (for SolveNormalLm), each counting its evaluations.
struct Decay {
  std::vector<double> t, y;
  Decay() {
    std::mt19937_64 rng(3);
    std::normal_distribution<double> noise(0.0, 0.02);
    for (int i = 0; i < 60; ++i) {
      t.push_back(0.1 * i);
      y.push_back(2.0 * std::exp(-0.7 * t.back()) + 0.3 + noise(rng));
    }
  }
  double Residual(const double* x, size_t i, double* j) const {
    const double e = std::exp(-x[1] * t[i]);
    if (j != nullptr) j[0] = e, j[1] = -x[0] * t[i] * e, j[2] = 1.0;
    return x[0] * e + x[2] - y[i];
  }
};

struct DecayResiduals {
  using Scalar = double;
  enum { NUM_RESIDUALS = Eigen::Dynamic, NUM_PARAMETERS = 3 };
  const Decay* decay;
  mutable int evaluations = 0;
  int NumResiduals() const { return static_cast<int>(decay->t.size()); }
  bool operator()(const double* x, double* residuals, double* jacobian) const {
    ++evaluations;
    const size_t n = decay->t.size();
    for (size_t i = 0; i < n; ++i) {
      double j[3];
      residuals[i] = decay->Residual(x, i, j);
      for (int k = 0; jacobian != nullptr && k < 3; ++k) jacobian[k * n + i] = j[k];
    }
    return true;
  }
};

class DecayNormal : public NormalProblem<3> {
 public:
  explicit DecayNormal(const Decay* decay) : decay_(decay) {}
  bool Evaluate(const double* x, bool want_normal, NormalEquations<3>* normal) const override {
    normal->cost2 = 0.0;
    normal->jtj.setZero();
    normal->jtr.setZero();
    for (size_t i = 0; i < decay_->t.size(); ++i) {
      Eigen::Vector3d j;
      const double r = decay_->Residual(x, i, j.data());
      normal->cost2 += r * r;
      if (want_normal) normal->jtj += j * j.transpose(), normal->jtr += j * r;
    }
    return true;
  }

 private:
  const Decay* decay_;
};

// The problem's minimum, to the rounding.
Eigen::Vector3d Minimum(const DecayNormal& problem) {
  NormalLmOptions tight;
  tight.function_tolerance = 1e-14;
  Eigen::Vector3d minimum(1.0, 0.2, 0.0);
  SolveNormalLm(problem, tight, &minimum);
  return minimum;
}

// The steps are TinySolver's: from the same start, the same solution, cost and number of
// evaluations (TinySolver evaluates again at an accepted step; SolveNormalLm counts that too).
TEST(NormalLm, TakesTinySolversSteps) {
  const Decay decay;
  for (const double tolerance : {1e-6, 1e-2, 0.5}) {
    DecayResiduals residuals{&decay};
    ceres::TinySolver<DecayResiduals> tiny;
    tiny.options.function_tolerance = tolerance;
    Eigen::Vector3d x_tiny(1.0, 0.2, 0.0);
    const auto& tiny_summary = tiny.Solve(residuals, &x_tiny);

    NormalLmOptions options;
    options.function_tolerance = tolerance;
    Eigen::Vector3d x(1.0, 0.2, 0.0);
    const NormalLmSummary summary = SolveNormalLm(DecayNormal(&decay), options, &x);
    EXPECT_NEAR((x - x_tiny).norm(), 0.0, 1e-10) << tolerance;
    EXPECT_NEAR(summary.final_cost, tiny_summary.final_cost, 1e-12) << tolerance;
    EXPECT_EQ(summary.evaluations, residuals.evaluations) << tolerance;
    EXPECT_FALSE(summary.decrement_stop);
  }
}

// The Newton decrement's stop: one evaluation fewer than the cost change's rule, at a point within
// sqrt(tolerance) standard errors of the minimum (the residuals' noise sd is 0.02 here, so the
// decrement in unit-variance terms is |r|^2's divided by 0.02^2).
TEST(NormalLm, TheDecrementStopSavesTheLastStep) {
  const Decay decay;
  const DecayNormal problem(&decay);
  const Eigen::Vector3d minimum = Minimum(problem);

  const double tolerance = 1e-4 * 0.02 * 0.02;  // 1e-4 in chi^2 units
  NormalLmOptions cost_rule, decrement_rule;
  cost_rule.function_tolerance = decrement_rule.function_tolerance = tolerance;
  decrement_rule.decrement_tolerance = tolerance;
  Eigen::Vector3d x_cost(1.0, 0.2, 0.0), x_decrement(1.0, 0.2, 0.0);
  const NormalLmSummary by_cost = SolveNormalLm(problem, cost_rule, &x_cost);
  const NormalLmSummary by_decrement = SolveNormalLm(problem, decrement_rule, &x_decrement);
  EXPECT_TRUE(by_decrement.decrement_stop);
  EXPECT_LT(by_decrement.evaluations, by_cost.evaluations);

  // Distance to the minimum in standard errors: (dx^T J^T J dx) / sd^2.
  NormalEquations<3> at_minimum;
  problem.Evaluate(minimum.data(), true, &at_minimum);
  const Eigen::Vector3d dx = x_decrement - minimum;
  EXPECT_LT(dx.dot(at_minimum.jtj * dx) / (0.02 * 0.02), 1e-4);
}

// The final step taken without evaluating the model: two evaluations fewer than the decrement's
// stop (the trial's cost and its normal equations, one computation of the blob fit's model), a
// point as close to the minimum as the decrement stop's (after a step within 3 standard errors
// what is left is second order), the predicted cost that point's own, and `evaluated` the point
// before the step.
TEST(NormalLm, TheFinalStepLandsAtTheMinimumUnevaluated) {
  const Decay decay;
  const DecayNormal problem(&decay);
  const Eigen::Vector3d minimum = Minimum(problem);

  const double chi2_unit = 0.02 * 0.02;  // the residuals' noise variance
  NormalLmOptions by_decrement, final_step;
  by_decrement.function_tolerance = final_step.function_tolerance = 1e-4 * chi2_unit;
  by_decrement.decrement_tolerance = final_step.decrement_tolerance = 1e-4 * chi2_unit;
  final_step.final_step_decrement = 9.0 * chi2_unit;
  Eigen::Vector3d x_decrement(1.0, 0.2, 0.0), x_final(1.0, 0.2, 0.0), evaluated;
  const NormalLmSummary a = SolveNormalLm(problem, by_decrement, &x_decrement);
  const NormalLmSummary b = SolveNormalLm(problem, final_step, &x_final, &evaluated);
  EXPECT_TRUE(b.final_step);
  EXPECT_FALSE(a.final_step);
  EXPECT_EQ(b.evaluations + 2, a.evaluations);

  NormalEquations<3> at_minimum, at_final, at_evaluated;
  problem.Evaluate(minimum.data(), true, &at_minimum);
  const Eigen::Vector3d dx = x_final - minimum;
  EXPECT_LT(dx.dot(at_minimum.jtj * dx) / chi2_unit, 1e-3);
  problem.Evaluate(x_final.data(), false, &at_final);
  EXPECT_NEAR(b.final_cost, 0.5 * at_final.cost2, 1e-3 * chi2_unit);
  // The point before the step: away from the final one, its decrement below the final step's rule.
  EXPECT_GT((evaluated - x_final).norm(), 0.0);
  problem.Evaluate(evaluated.data(), true, &at_evaluated);
  const Eigen::Vector3d g = at_evaluated.jtr;
  EXPECT_LT(g.dot(at_evaluated.jtj.ldlt().solve(g)), 9.0 * chi2_unit);
}

// Options refuse each bad field by name, and the solver refuses bad options.
TEST(NormalLmOptions, RefusesEachBadFieldByName) {
  std::string why;
  EXPECT_TRUE(NormalLmOptions().IsValid(&why)) << why;
  NormalLmOptions o;
  o.max_iterations = 0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("max_iterations"), std::string::npos) << why;
  o = NormalLmOptions();
  o.function_tolerance = -1.0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("function_tolerance"), std::string::npos) << why;
  o = NormalLmOptions();
  o.decrement_tolerance = NAN;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("decrement_tolerance"), std::string::npos) << why;
  o = NormalLmOptions();
  o.final_step_decrement = -1.0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("final_step_decrement"), std::string::npos) << why;
  o = NormalLmOptions();
  o.initial_trust_region_radius = 0.0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("initial_trust_region_radius"), std::string::npos) << why;
  EXPECT_FALSE(o.IsValid(nullptr));
  const Decay decay;
  const DecayNormal problem(&decay);
  Eigen::Vector3d x(1.0, 0.2, 0.0);
  EXPECT_THROW(SolveNormalLm(problem, o, &x), CheckError);
}

}  // namespace
}  // namespace irdist
