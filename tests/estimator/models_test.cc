#include "estimator/models.h"

#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <set>

#include "tests/estimator/synthetic.h"

namespace irdist {
namespace {

int ActiveCount(ModelKind kind, ModelForm form) {
  const ModelSpec& spec = GetModelSpec(kind);
  int n = 0;
  for (int j = 0; j < spec.num_coefficients(); ++j) n += IsTermActive(spec, form, j);
  return n;
}

TEST(Models, TableSizesMatchThePaper) {
  EXPECT_EQ(GetModelSpec(ModelKind::kDirectE).num_coefficients(), 16);
  EXPECT_EQ(GetModelSpec(ModelKind::kDirectF).num_coefficients(), 16);
  EXPECT_EQ(GetModelSpec(ModelKind::kDirectSigma).num_coefficients(), 24);
  EXPECT_EQ(GetModelSpec(ModelKind::kDiffE).num_coefficients(), 8);
  EXPECT_EQ(GetModelSpec(ModelKind::kDiffF).num_coefficients(), 8);
  EXPECT_EQ(GetModelSpec(ModelKind::kDiffSigma).num_coefficients(), 12);
  EXPECT_EQ(GetModelSpec(ModelKind::kFreeE).num_coefficients(), 17);
  EXPECT_EQ(GetModelSpec(ModelKind::kFreeE).num_denominator, 4);
  EXPECT_EQ(GetModelSpec(ModelKind::kFreeSigma).num_coefficients(), 22);
  EXPECT_EQ(GetModelSpec(ModelKind::kFreeSigma).num_denominator, 4);
  EXPECT_EQ(ActiveCount(ModelKind::kFreeE, ModelForm::kReduced), 8);
  EXPECT_EQ(ActiveCount(ModelKind::kFreeSigma, ModelForm::kReduced), 10);
  EXPECT_EQ(ActiveCount(ModelKind::kDirectSigma, ModelForm::kReduced), 24);
}

TEST(Models, NoDuplicateMonomials) {  // catches the paper's p4/p5 typo
  for (int k = 0; k < kNumModelKinds; ++k) {
    const ModelSpec& spec = GetModelSpec(static_cast<ModelKind>(k));
    std::set<std::pair<bool, std::array<int8_t, kNumModelVars>>> seen;
    for (int j = 0; j < spec.num_coefficients(); ++j) {
      EXPECT_TRUE(seen.insert({j < spec.num_numerator, spec.terms[j].exponent}).second)
          << ToString(spec.kind) << " " << spec.terms[j].name;
    }
  }
  EXPECT_STREQ(GetModelSpec(ModelKind::kFreeSigma).terms[4].name, "p5");
  EXPECT_EQ(GetModelSpec(ModelKind::kFreeSigma).terms[4].exponent[kVarD], 2);
}

TEST(Models, RhoIsAGaussianWithNegativeExponent) {
  EXPECT_DOUBLE_EQ(Rho(0.0, 20.0), 1.0);
  EXPECT_NEAR(Rho(20.0, 20.0), std::exp(-0.5), 1e-15);
  EXPECT_LT(Rho(30.0, 20.0), Rho(10.0, 20.0));
}

TEST(Models, DifferentialIsTheDifferenceOfDirect) {
  const testing::SyntheticRig rig;
  for (auto [direct, diff] : {std::pair{ModelKind::kDirectE, ModelKind::kDiffE},
                              std::pair{ModelKind::kDirectF, ModelKind::kDiffF},
                              std::pair{ModelKind::kDirectSigma, ModelKind::kDiffSigma}}) {
    const double m = rig.Feature(direct, 32.0, 490.0, 2100.0, 17.0);
    const double r = rig.Feature(direct, 8.0, 490.0, 2100.0, 17.0);
    ModelInputs in{2100.0, 17.0, 0.0, 490.0, 24.0, 0.0};
    const double pred = PredictModel(diff, rig.Coefficients(diff), rig.sigma_deg, rig.scaling, in);
    EXPECT_NEAR(pred, m - r, 1e-12 * std::abs(m - r)) << ToString(diff);
  }
}

TEST(Models, FreeModelsEliminateI0) {
  const testing::SyntheticRig rig;
  for (double bias : {400.0, 500.0, 650.0}) {
    const double t = 34.0, d = 2600.0, theta = 22.0;
    const double de = rig.Feature(ModelKind::kDirectE, t, bias, d, theta) -
                      rig.Feature(ModelKind::kDirectE, 8.0, bias, d, theta);
    const double df = rig.Feature(ModelKind::kDirectF, t, bias, d, theta) -
                      rig.Feature(ModelKind::kDirectF, 8.0, bias, d, theta);
    const double ds = rig.Feature(ModelKind::kDirectSigma, t, bias, d, theta) -
                      rig.Feature(ModelKind::kDirectSigma, 8.0, bias, d, theta);
    ModelInputs in{d, theta, 0.0, 0.0, t - 8.0, df};  // no I0 given
    EXPECT_NEAR(PredictModel(ModelKind::kFreeE, rig.Coefficients(ModelKind::kFreeE), rig.sigma_deg,
                             rig.scaling, in),
                de, 1e-12 * de);
    EXPECT_NEAR(PredictModel(ModelKind::kFreeSigma, rig.Coefficients(ModelKind::kFreeSigma),
                             rig.sigma_deg, rig.scaling, in),
                ds, 1e-12 * ds);
  }
}

TEST(Models, GaugeScalingAllCoefficientsLeavesPredictionsUnchanged) {
  const testing::SyntheticRig rig;
  for (ModelKind k : {ModelKind::kFreeE, ModelKind::kFreeSigma}) {
    std::vector<double> c = rig.Coefficients(k);
    ModelInputs in{1800.0, 12.0, 0.0, 0.0, 26.0, 3.5};
    const double before = PredictModel(k, c, rig.sigma_deg, rig.scaling, in);
    for (double& v : c) v *= -37.25;
    EXPECT_NEAR(PredictModel(k, c, rig.sigma_deg, rig.scaling, in), before,
                1e-14 * std::abs(before));
  }
}

TEST(Models, JetEvaluationMatchesDoubleAndFiniteDifferences) {
  const testing::SyntheticRig rig;
  const ModelSpec& spec = GetModelSpec(ModelKind::kFreeSigma);
  const std::vector<double> c = rig.Coefficients(ModelKind::kFreeSigma);
  using J = ceres::Jet<double, 1>;
  auto value = [&](double big_d) {
    double v[kNumModelVars] = {big_d, Rho(15.0, rig.sigma_deg), 0, 0, 0.9, 4.0};
    return EvaluateModel(spec, c.data(), v);
  };
  J v[kNumModelVars] = {J(0.8, 0), J(Rho(15.0, rig.sigma_deg)), J(0), J(0), J(0.9), J(4.0)};
  const J out = EvaluateModel(spec, c.data(), v);
  EXPECT_DOUBLE_EQ(out.a, value(0.8));
  const double h = 1e-6;
  EXPECT_NEAR(out.v[0], (value(0.8 + h) - value(0.8 - h)) / (2 * h), 1e-6 * std::abs(out.v[0]));
}

TEST(Models, AlgebraicPolynomialVanishesAtTheTrueD) {
  const testing::SyntheticRig rig;
  const double d = 2300.0, theta = 25.0, bias = 480.0, t = 30.0;
  const double df = rig.Feature(ModelKind::kDirectF, t, bias, d, theta) -
                    rig.Feature(ModelKind::kDirectF, 8.0, bias, d, theta);
  const double ds = rig.Feature(ModelKind::kDirectSigma, t, bias, d, theta) -
                    rig.Feature(ModelKind::kDirectSigma, 8.0, bias, d, theta);
  double vars[kNumModelVars] = {0, Rho(theta, rig.sigma_deg), 0, 0, (t - 8.0) / 30.0, df};
  double poly[4];
  const std::vector<double> p = rig.Coefficients(ModelKind::kFreeSigma);
  AlgebraicPolynomialInD(GetModelSpec(ModelKind::kFreeSigma), p.data(), vars, ds, poly);
  const double x = rig.scaling.ScaledD(d);
  const double value = ((poly[3] * x + poly[2]) * x + poly[1]) * x + poly[0];
  double scale = 0.0;
  for (double v : poly) scale = std::max(scale, std::abs(v));
  EXPECT_NEAR(value, 0.0, 1e-12 * scale);
  EXPECT_NE(poly[3], 0.0);  // the full form's c1 term
}

TEST(Models, NamesRoundTrip) {
  for (int k = 0; k < kNumModelKinds; ++k) {
    ModelKind parsed;
    ASSERT_TRUE(ParseModelKind(ToString(static_cast<ModelKind>(k)), &parsed));
    EXPECT_EQ(static_cast<int>(parsed), k);
  }
  ModelKind kind;
  EXPECT_FALSE(ParseModelKind("eq17", &kind));
}

}  // namespace
}  // namespace irdist
