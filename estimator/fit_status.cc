#include "estimator/fit_status.h"

#include <ceres/ceres.h>

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>

namespace irdist {
namespace {

// "0.707 q3 - 0.707 q5": the components of a unit vector above 0.1, largest first (at most 6).
std::string DescribeDirection(const Eigen::VectorXd& v, const std::vector<std::string>& names) {
  std::vector<int> order(v.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(),
            [&](int a, int b) { return std::abs(v(a)) > std::abs(v(b)); });
  // Sign convention: the largest component positive.
  const double sign = v.size() > 0 && v(order.front()) < 0.0 ? -1.0 : 1.0;
  std::ostringstream out;
  out.precision(3);
  int shown = 0;
  for (int i : order) {
    const double c = sign * v(i);
    if (std::abs(c) < 0.1 || shown == 6) break;
    const std::string name =
        i < static_cast<int>(names.size()) ? names[i] : "x" + std::to_string(i);
    out << (shown == 0 ? (c < 0 ? "-" : "") : (c < 0 ? " - " : " + ")) << std::abs(c) << " "
        << name;
    ++shown;
  }
  return out.str();
}

Eigen::MatrixXd DenseJacobian(ceres::Problem* problem, const std::vector<double*>& blocks) {
  ceres::CRSMatrix jacobian;
  ceres::Problem::EvaluateOptions eval;
  eval.parameter_blocks = blocks;
  if (!problem->Evaluate(eval, nullptr, nullptr, nullptr, &jacobian)) return Eigen::MatrixXd();
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(jacobian.num_rows, jacobian.num_cols);
  for (int r = 0; r < jacobian.num_rows; ++r) {
    for (int k = jacobian.rows[r]; k < jacobian.rows[r + 1]; ++k) {
      dense(r, jacobian.cols[k]) = jacobian.values[k];
    }
  }
  return dense;
}

}  // namespace

FitConditioning ClassifyJacobian(const Eigen::MatrixXd& jacobian,
                                 const std::vector<std::string>& names) {
  FitConditioning out;
  out.parameters = static_cast<int>(jacobian.cols());
  if (jacobian.cols() == 0 || jacobian.rows() == 0) return out;
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(jacobian, Eigen::ComputeFullV);
  const Eigen::VectorXd s = svd.singularValues();  // descending, min(rows, cols) of them
  const double s_max = s(0);
  const double s_min = s.size() < jacobian.cols() ? 0.0 : s(s.size() - 1);
  out.condition_number = s_min > 0.0 ? s_max / s_min : std::numeric_limits<double>::infinity();
  out.rank = 0;
  const double tolerance =
      std::max(jacobian.rows(), jacobian.cols()) * std::numeric_limits<double>::epsilon() * s_max;
  for (int i = 0; i < s.size(); ++i) out.rank += s(i) > tolerance ? 1 : 0;
  // Columns beyond the rows (more parameters than residuals) are null directions too.
  for (int i = out.rank; i < jacobian.cols(); ++i) {
    out.null_directions.push_back(DescribeDirection(svd.matrixV().col(i), names));
  }
  return out;
}

std::vector<std::string> FreeParameterNames(const ModelSpec& spec, ModelForm form, int gauge,
                                            bool sigma_free) {
  std::vector<std::string> names;
  for (int j = 0; j < spec.num_coefficients(); ++j) {
    if (j != gauge && IsTermActive(spec, form, j)) names.push_back(spec.terms[j].name);
  }
  if (sigma_free) names.push_back("sigma");
  return names;
}

std::string FitConditioning::Note() const {
  std::ostringstream note;
  if (degenerate()) {
    note << "rank " << rank << " of " << parameters << "; null directions:";
    const size_t shown = std::min<size_t>(null_directions.size(), 4);
    for (size_t i = 0; i < shown; ++i) note << " [" << null_directions[i] << "]";
    if (shown < null_directions.size())
      note << " and " << null_directions.size() - shown << " more";
  } else if (ill_conditioned()) {
    note << "condition number above " << kIllConditionedLimit;
  }
  return note.str();
}

FitConditioning ConditioningOf(ceres::Problem* problem, const std::vector<double*>& blocks,
                               const std::vector<std::string>& names) {
  return ClassifyJacobian(DenseJacobian(problem, blocks), names);
}

}  // namespace irdist
