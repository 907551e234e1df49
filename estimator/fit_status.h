#pragma once
// What a least-squares fit is, read from its Jacobian at the solution: converged (full rank and
// well conditioned), degenerate (rank-deficient: some combination of the parameters does not
// change the residuals at all; those null directions are named) or ill-conditioned (full rank,
// but the singular-value ratio is above a stated limit, so the coefficients carry few digits).

#include <Eigen/Core>
#include <string>
#include <vector>

#include "estimator/models.h"

namespace ceres {
class Problem;
}

namespace irdist {

// The numerical rank: singular values above max(rows, cols) * machine epsilon * s_max (the
// tolerance of LAPACK's and NumPy's rank), below which a direction is lost to rounding.
// Above this singular-value ratio of J (1e20 for J^T J) the solution's coefficients keep fewer
// than ~6 significant digits: the fit is reported ill-conditioned.
constexpr double kIllConditionedLimit = 1e10;

struct FitConditioning {
  double condition_number = -1.0;  // s_max / s_min (infinity when s_min is 0), -1 if no column
  int rank = 0;                    // numerical rank (above)
  int parameters = 0;              // columns of the Jacobian
  // One line per null direction: the unit right singular vector, its largest components named,
  // e.g. "0.707 q3 - 0.707 q5".
  std::vector<std::string> null_directions;
  bool degenerate() const { return rank < parameters; }
  bool ill_conditioned() const { return !degenerate() && condition_number > kIllConditionedLimit; }
  // "rank 16 of 17; null directions: [0.707 q3 - 0.707 q5]" / "condition number above 1e+10" /
  // "" when well conditioned.
  std::string Note() const;
};

// Classifies from the Jacobian (rows: residuals, columns: free parameters named by `names`).
FitConditioning ClassifyJacobian(const Eigen::MatrixXd& jacobian,
                                 const std::vector<std::string>& names);

// The free parameters of a ratio/polynomial model fit, in the Jacobian's column order: the active
// coefficients other than the gauge, by their names in the paper's tables ("q5", "p15"), then
// "sigma" when it is free.
std::vector<std::string> FreeParameterNames(const ModelSpec& spec, ModelForm form, int gauge,
                                            bool sigma_free);

// The Jacobian of `problem` at its current parameters with respect to `blocks` (none of them
// constant; columns named by `names`), classified.
FitConditioning ConditioningOf(ceres::Problem* problem, const std::vector<double*>& blocks,
                               const std::vector<std::string>& names);

}  // namespace irdist
