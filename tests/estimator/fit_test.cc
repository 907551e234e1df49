#include "estimator/fit.h"

#include <gtest/gtest.h>

#include <cmath>

#include "base/check.h"
#include "tests/estimator/synthetic.h"

namespace irdist {
namespace {

// Largest relative difference between the fitted model and the truth over the samples and over
// poses between the calibration grid's nodes.
double WorstPredictionError(const CalibrationModel& fitted, const FittedModel& m,
                            const testing::SyntheticRig& rig) {
  double worst = 0.0;
  for (double d : {1500.0, 1730.0, 2450.0, 3000.0}) {
    for (double theta : {0.0, 7.5, 21.0, 35.0}) {
      for (double bias : {475.0, 490.0, 500.0}) {
        for (double t : {30.0, 33.0, 36.0}) {
          const Features ref = rig.Frame(8.0, bias, d, theta, theta);
          const Features meas = rig.Frame(t, bias, d, theta, theta);
          ModelInputs in{d, theta, t, bias, t - 8.0, meas.f00 - ref.f00};
          double truth = 0.0;
          switch (m.kind) {
            case ModelKind::kFreeE:
            case ModelKind::kDiffE:
              truth = meas.e_rel - ref.e_rel;
              break;
            case ModelKind::kDiffF:
              truth = meas.f00 - ref.f00;
              break;
            case ModelKind::kFreeSigma:
            case ModelKind::kDiffSigma:
              truth = meas.sigma - ref.sigma;
              break;
            case ModelKind::kDirectE:
              truth = meas.e_rel;
              break;
            case ModelKind::kDirectF:
              truth = meas.f00;
              break;
            case ModelKind::kDirectSigma:
              truth = meas.sigma;
              break;
          }
          worst = std::max(worst, std::abs(m.Predict(fitted.scaling, in) / truth - 1.0));
        }
      }
    }
  }
  return worst;
}

TEST(FitOptions, DefaultsAreValid) {
  std::string why;
  EXPECT_TRUE(FitOptions().IsValid(&why)) << why;
  FitOptions bad;
  bad.multi_starts = 0;
  EXPECT_FALSE(bad.IsValid(&why));
}

TEST(Fit, FullFormRecoversPredictionsFromAColdStart) {
  const testing::SyntheticRig rig;
  FitOptions options;
  options.free_form = ModelForm::kFull;
  const CalibrationModel model = Fit(rig.Table3(), FeatureOptions(), options);
  ASSERT_EQ(model.models.size(), 8u);
  for (const FittedModel& m : model.models) {
    SCOPED_TRACE(ToString(m.kind));
    EXPECT_NE(m.summary.termination, FitSummary::Termination::kFailed) << m.summary.BriefReport();
    EXPECT_LT(m.summary.max_relative_error, 1e-7) << m.summary.BriefReport();
    EXPECT_LT(WorstPredictionError(model, m, rig), 1e-6) << m.summary.BriefReport();
    EXPECT_NEAR(m.sigma_deg, rig.sigma_deg, 1e-3 * rig.sigma_deg);
    EXPECT_FALSE(m.degenerate);
    EXPECT_GT(m.summary.condition_number, 1.0);
    EXPECT_EQ(m.summary.residuals.size(), static_cast<size_t>(m.summary.samples));
    if (GetModelSpec(m.kind).has_denominator()) {
      ASSERT_GE(m.summary.gauge_index, 0);
      EXPECT_EQ(m.coefficients[m.summary.gauge_index], 1.0);  // the scale gauge
    }
    std::printf("%-13s %s\n", ToString(m.kind), m.summary.BriefReport().c_str());
  }
  EXPECT_EQ(model.models[6].summary.samples, 256);
  EXPECT_EQ(model.models[0].summary.samples, 320);  // each frame once
  EXPECT_DOUBLE_EQ(model.ranges.d_min_mm, 1500.0);
  EXPECT_DOUBLE_EQ(model.ranges.theta_max_deg, 35.0);
}

TEST(Fit, ReducedFormIsExactWithoutBackground) {
  testing::SyntheticRig rig;
  rig.e.r2 = rig.f.r2 = rig.s.r2 = 0.0;  // no I0-independent background: dt^2 terms vanish
  FitOptions options;
  options.models = {ModelKind::kFreeE, ModelKind::kFreeSigma};
  options.free_form = ModelForm::kReduced;
  const CalibrationModel model = Fit(rig.Table3(), FeatureOptions(), options);
  for (const FittedModel& m : model.models) {
    EXPECT_EQ(m.form, ModelForm::kReduced);
    std::printf("%-13s reduced: %s\n", ToString(m.kind), m.summary.BriefReport().c_str());
    EXPECT_LT(WorstPredictionError(model, m, rig), 1e-6) << m.summary.BriefReport();
    const ModelSpec& spec = GetModelSpec(m.kind);
    for (int j = 0; j < spec.num_coefficients(); ++j) {
      if (!IsTermActive(spec, ModelForm::kReduced, j)) {
        EXPECT_EQ(m.coefficients[j], 0.0);
      }
    }
  }
}

TEST(Fit, FixedWindowEEquationIsFlaggedDegenerate) {
  const testing::SyntheticRig rig;
  std::vector<CalibrationSample> samples = rig.Table3();
  for (CalibrationSample& s : samples) {  // E_rel = F / A, as with a fixed window
    s.reference.e_rel = s.reference.f00 / 4096.0;
    s.measurement.e_rel = s.measurement.f00 / 4096.0;
  }
  FitOptions options;
  options.models = {ModelKind::kFreeE, ModelKind::kDirectE};
  const CalibrationModel model = Fit(samples, FeatureOptions(), options);
  EXPECT_TRUE(model.Find(ModelKind::kFreeE)->degenerate);
  EXPECT_TRUE(model.Find(ModelKind::kDirectE)->degenerate);
}

TEST(Fit, NoisyFeaturesGiveSmallResiduals) {
  const testing::SyntheticRig rig;
  std::vector<CalibrationSample> samples = rig.Table3();
  std::srand(7);
  auto noisy = [](double v) { return v * (1.0 + 1e-3 * (2.0 * std::rand() / RAND_MAX - 1.0)); };
  for (CalibrationSample& s : samples) {
    for (Features* f : {&s.reference, &s.measurement}) {
      f->e_rel = noisy(f->e_rel);
      f->f00 = noisy(f->f00);
      f->sigma = noisy(f->sigma);
    }
  }
  FitOptions options;
  options.models = {ModelKind::kFreeE, ModelKind::kFreeSigma};
  options.free_form = ModelForm::kFull;
  const CalibrationModel model = Fit(samples, FeatureOptions(), options);
  for (const FittedModel& m : model.models) {
    // 0.1% on each feature is ~0.15% on a difference; the fit's mean error stays below 0.5%.
    EXPECT_LT(m.summary.mean_relative_error, 5e-3) << m.summary.BriefReport();
    EXPECT_LT(WorstPredictionError(model, m, rig), 2e-2) << m.summary.BriefReport();
  }
}

TEST(Fit, GeometricBaselineRecoversSizeLaw) {
  const testing::SyntheticRig rig;
  const GeometricModel g = FitGeometric(rig.Table3());
  EXPECT_NEAR(g.alpha_px2, 30.0, 1e-9);
  EXPECT_NEAR(g.beta_px2, 1.0, 1e-9);
  EXPECT_LT(g.summary.max_relative_error, 1e-12);
}

// Table 3 samples whose moment variance carries a relative error growing as d^1.5 (every pose's
// error drawn from {-1, +1} x sd, so each distance's rms is exactly the sd): the noise model
// returns the law.
TEST(Fit, GeometricNoiseModelFollowsTheResidualsAcrossDistance) {
  const testing::SyntheticRig rig;
  std::vector<CalibrationSample> samples = rig.Table3();
  int i = 0;
  for (CalibrationSample& s : samples) {
    const double sd_d = 4e-4 * std::pow(s.d_mm / 1000.0, 1.5);  // relative error of d
    // d_est = d (1 + e) from var - beta = alpha D / (1 + e)^2.
    const double e = (i++ % 2 == 0 ? 1.0 : -1.0) * sd_d;
    Features& m = s.measurement;
    m.moment_major_var_px2 = 1.0 + (m.moment_major_var_px2 - 1.0) / ((1.0 + e) * (1.0 + e));
  }
  const GeometricModel g = FitGeometric(samples);
  EXPECT_NEAR(g.noise_exponent, 1.5, 0.05);
  EXPECT_NEAR(g.NoiseRel(2000.0), 4e-4 * std::pow(2.0, 1.5), 0.05 * 4e-4 * std::pow(2.0, 1.5));
  // No noise model: NoiseRel is 0 (standard errors stay in units of the mean fit error).
  EXPECT_EQ(GeometricModel().NoiseRel(2000.0), 0.0);
}

// Table 3 samples whose moment ellipse is distorted: x = (minor - blur) / (major - blur) =
// 0.97 cos^2(theta) + 0.01 + 0.005 z (z the distance mapped to [-1, 1] over 1.5..3 m), the kind of
// pose-dependent deviation a threshold cut or an unmodelled blur leaves.
std::vector<CalibrationSample> DistortedEllipses(const testing::SyntheticRig& rig) {
  std::vector<CalibrationSample> samples = rig.Table3();
  for (CalibrationSample& s : samples) {
    const double c = std::cos(s.theta_deg * M_PI / 180.0);
    const double z = (s.d_mm - 2250.0) / 750.0;
    const double x = 0.97 * c * c + 0.01 + 0.005 * z;
    Features& m = s.measurement;
    m.moment_minor_var_px2 = 1.0 + x * (m.moment_major_var_px2 - 1.0);
  }
  return samples;
}

TEST(Fit, ThetaCorrectionRemovesASmoothEllipseBias) {
  const testing::SyntheticRig rig;
  const std::vector<CalibrationSample> samples = DistortedEllipses(rig);
  const GeometricModel g = FitGeometric(samples);
  for (int degree : {1, 2, 3}) {
    const ThetaCorrection tc = FitThetaCorrection(samples, g, degree);
    ASSERT_TRUE(tc.fitted()) << tc.summary.message;
    EXPECT_EQ(static_cast<int>(tc.coefficients.size()), ThetaCorrection::NumTerms(degree));
    EXPECT_LT(tc.summary.max_relative_error, 1e-5) << "degree " << degree;  // degrees
    EXPECT_NEAR(tc.d_min_mm, 1500.0, 1e-6);
    EXPECT_NEAR(tc.d_max_mm, 3000.0, 1e-6);
  }
  // Off the calibration grid: 1.7 m, 22 deg; the uncorrected ratio is more than 1 deg off.
  const ThetaCorrection tc = FitThetaCorrection(samples, g, 2);
  const double major = 30.0 * (1000.0 / 1700.0) * (1000.0 / 1700.0) + 1.0;
  const double c = std::cos(22.0 * M_PI / 180.0);
  const double x = 0.97 * c * c + 0.01 + 0.005 * (1700.0 - 2250.0) / 750.0;
  const double minor = 1.0 + x * (major - 1.0);
  EXPECT_NEAR(tc.ThetaDeg(major, minor, g), 22.0, 1e-4);
  EXPECT_GT(std::abs(ThetaCorrection().ThetaDeg(major, minor, g) - 22.0), 1.0);
  // No extrapolation: a distance beyond the calibrated range is read at its edge, and a rounder
  // blob than any calibrated one at the calibrated maximum of x.
  const double far_major = 30.0 * (1000.0 / 6000.0) * (1000.0 / 6000.0) + 1.0;
  const double far_minor = 1.0 + x * (far_major - 1.0);
  EXPECT_TRUE(std::isfinite(tc.ThetaDeg(far_major, far_minor, g)));
  EXPECT_NEAR(tc.ThetaDeg(major, major, g),
              tc.ThetaDeg(major, 1.0 + tc.ratio_sq_max * (major - 1.0), g), 1e-9);
  EXPECT_NEAR(tc.ThetaDeg(far_major, far_minor, g),
              tc.ThetaDeg(30.0 * (1000.0 / 3000.0) * (1000.0 / 3000.0) + 1.0,
                          1.0 + x * 30.0 * (1000.0 / 3000.0) * (1000.0 / 3000.0), g),
              1e-6);
  // Not larger than the blur: NaN.
  EXPECT_TRUE(std::isnan(tc.ThetaDeg(0.5, 0.5, g)));
}

TEST(Fit, ThetaCorrectionNeedsAnEllipse) {
  // The plain synthetic frames have no minor axis (every x is 0): rank-deficient, not fitted.
  const testing::SyntheticRig rig;
  const std::vector<CalibrationSample> samples = rig.Table3();
  const ThetaCorrection tc = FitThetaCorrection(samples, FitGeometric(samples), 2);
  EXPECT_FALSE(tc.fitted());
  EXPECT_FALSE(tc.summary.message.empty());
  // Without a geometric model there is no blur variance to remove.
  EXPECT_FALSE(FitThetaCorrection(samples, GeometricModel(), 2).fitted());
  EXPECT_THROW(FitThetaCorrection(samples, FitGeometric(samples), 4), CheckError);
}

TEST(Fit, TooFewSamplesIsACheckError) {
  const testing::SyntheticRig rig;
  std::vector<CalibrationSample> samples = rig.Table3();
  samples.resize(5);
  EXPECT_THROW(
      FitModel(ModelKind::kFreeSigma, ModelForm::kFull, samples, rig.scaling, FitOptions()),
      CheckError);
}

}  // namespace
}  // namespace irdist
