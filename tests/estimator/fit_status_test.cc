#include "estimator/fit_status.h"

#include <gtest/gtest.h>

#include "estimator/fit.h"

namespace irdist {
namespace {

TEST(FitStatus, WellConditionedJacobianIsFullRank) {
  Eigen::MatrixXd j(3, 2);
  j << 1, 0, 0, 2, 1, 1;
  const FitConditioning c = ClassifyJacobian(j, {"a", "b"});
  EXPECT_EQ(c.rank, 2);
  EXPECT_FALSE(c.degenerate());
  EXPECT_FALSE(c.ill_conditioned());
  EXPECT_LT(c.condition_number, 10.0);
  EXPECT_TRUE(c.null_directions.empty());
}

TEST(FitStatus, EqualColumnsAreDegenerateWithTheirNullDirectionNamed) {
  Eigen::MatrixXd j(4, 3);
  j << 1, 1, 0, 2, 2, 1, 3, 3, 0, 4, 4, 1;  // a and b enter only as a + b
  const FitConditioning c = ClassifyJacobian(j, {"q1", "q2", "sigma"});
  EXPECT_TRUE(c.degenerate());
  EXPECT_EQ(c.rank, 2);
  ASSERT_EQ(c.null_directions.size(), 1u);
  EXPECT_NE(c.Note().find("rank 2 of 3"), std::string::npos) << c.Note();
  const std::string& d = c.null_directions[0];  // "0.707 q1 - 0.707 q2" or its mirror
  EXPECT_TRUE(d == "0.707 q1 - 0.707 q2" || d == "0.707 q2 - 0.707 q1") << d;
}

TEST(FitStatus, MoreParametersThanResidualsIsDegenerate) {
  Eigen::MatrixXd j(1, 2);
  j << 1, 2;
  const FitConditioning c = ClassifyJacobian(j, {"a", "b"});
  EXPECT_TRUE(c.degenerate());
  EXPECT_EQ(c.null_directions.size(), 1u);
}

TEST(FitStatus, LargeConditionNumberIsIllConditioned) {
  Eigen::MatrixXd j = Eigen::MatrixXd::Identity(3, 2);
  j(1, 1) = 1e-11;  // ratio 1e11: above kIllConditionedLimit, above the rank tolerance (7e-16)
  const FitConditioning c = ClassifyJacobian(j, {"a", "b"});
  EXPECT_FALSE(c.degenerate());
  EXPECT_TRUE(c.ill_conditioned());
  EXPECT_NEAR(c.condition_number, 1e11, 1e5);
}

TEST(FitStatus, ADirectionBelowTheRoundingOfTheLargestIsLost) {
  Eigen::MatrixXd j = Eigen::MatrixXd::Identity(3, 2);
  j(1, 1) = 1e-17;  // below 3 * 2.2e-16
  const FitConditioning c = ClassifyJacobian(j, {"a", "b"});
  EXPECT_TRUE(c.degenerate());
  ASSERT_EQ(c.null_directions.size(), 1u);
  EXPECT_EQ(c.null_directions[0], "1 b");
}

TEST(FitStatus, TerminationNamesAreDistinct) {
  EXPECT_STREQ(ToString(FitSummary::Termination::kDegenerate), "degenerate");
  EXPECT_STREQ(ToString(FitSummary::Termination::kIllConditioned), "ill-conditioned");
  EXPECT_STREQ(ToString(FitSummary::Termination::kConverged), "converged");
}

TEST(FitStatus, FreeParametersSkipTheGaugeAndAddSigma) {
  const ModelSpec& spec = GetModelSpec(ModelKind::kFreeSigma);
  const auto names = FreeParameterNames(spec, ModelForm::kFull, spec.num_numerator, true);
  ASSERT_FALSE(names.empty());
  EXPECT_EQ(names.back(), "sigma");
  for (const std::string& n : names) EXPECT_NE(n, spec.terms[spec.num_numerator].name);
}

}  // namespace
}  // namespace irdist
