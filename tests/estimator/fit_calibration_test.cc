#include "estimator/fit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "base/check.h"
#include "tests/estimator/synthetic.h"

namespace irdist {
namespace {

// One cheap model: the whole model's assembly is under test here, not the models' fits.
FitOptions OneModel() {
  FitOptions options;
  options.models = {ModelKind::kDirectF};
  return options;
}

// The calibrated domain is the samples' own extremes: Table 3's grid is 1.5-3 m, 0-35 deg,
// 30-36 ms against an 8 ms reference, 475-500 mA.
TEST(FitCalibration, RangesAreTheSamplesExtremes) {
  const testing::SyntheticRig rig;
  std::vector<CalibrationSample> samples = rig.Table3();
  samples.back().t_ref_ms = 6.0;
  const CalibrationModel model = Fit(samples, FeatureOptions(), OneModel());
  const CalibratedRanges& r = model.ranges;
  EXPECT_EQ(r.d_min_mm, 1500.0);
  EXPECT_EQ(r.d_max_mm, 3000.0);
  EXPECT_EQ(r.theta_min_deg, 0.0);
  EXPECT_EQ(r.theta_max_deg, 35.0);
  EXPECT_EQ(r.t_min_ms, 30.0);
  EXPECT_EQ(r.t_max_ms, 36.0);
  EXPECT_EQ(r.t_ref_min_ms, 6.0);
  EXPECT_EQ(r.t_ref_max_ms, 8.0);
  EXPECT_EQ(r.bias_min_ma, 475.0);
  EXPECT_EQ(r.bias_max_ma, 500.0);
  // No frame with a peak level: the signal range is not recorded (0, 0).
  EXPECT_EQ(r.peak_min, 0.0);
  EXPECT_EQ(r.peak_max, 0.0);
}

// The signal range spans the usable frames' peaks, references and measurements alike; a
// saturated or border frame's peak says nothing of the calibrated signal.
TEST(FitCalibration, PeakRangeSpansTheUsableFrames) {
  const testing::SyntheticRig rig;
  std::vector<CalibrationSample> samples = rig.Table3();
  for (size_t i = 0; i < samples.size(); ++i) {
    samples[i].reference.peak = 0.3;
    samples[i].measurement.peak = 0.5;
  }
  samples[3].reference.peak = 0.12;       // the dimmest: a reference frame
  samples[7].measurement.peak = 0.81;     // the brightest usable
  samples[9].measurement.peak = 1.0;      // saturated: left out
  samples[9].measurement.saturated_pixels = 4;
  samples[11].reference.peak = 0.01;      // on the border: left out
  samples[11].reference.touches_border = true;
  const CalibrationModel model = Fit(samples, FeatureOptions(), OneModel());
  EXPECT_EQ(model.ranges.peak_min, 0.12);
  EXPECT_EQ(model.ranges.peak_max, 0.81);
}

// Every model asked for, in the order asked; the I0-free models in the options' form, the others
// in their full form; the feature options recorded as given.
TEST(FitCalibration, FitsTheModelsAskedForInTheirForms) {
  const testing::SyntheticRig rig;
  FitOptions options;
  options.models = {ModelKind::kFreeE, ModelKind::kDiffF, ModelKind::kDirectF};
  options.free_form = ModelForm::kReduced;
  options.multi_starts = 1;
  FeatureOptions features;
  features.window_side_px = 48;
  const CalibrationModel model = Fit(rig.Table3(), features, options);
  ASSERT_EQ(model.models.size(), 3u);
  EXPECT_EQ(model.models[0].kind, ModelKind::kFreeE);
  EXPECT_EQ(model.models[0].form, ModelForm::kReduced);
  EXPECT_EQ(model.models[1].kind, ModelKind::kDiffF);
  EXPECT_EQ(model.models[1].form, ModelForm::kFull);
  EXPECT_EQ(model.models[2].kind, ModelKind::kDirectF);
  EXPECT_EQ(model.models[2].form, ModelForm::kFull);
  EXPECT_EQ(model.Find(ModelKind::kFreeSigma), nullptr);
  ASSERT_NE(model.Find(ModelKind::kDirectF), nullptr);
  // F's direct model is exact on these features (Table 2's product form).
  EXPECT_LT(model.Find(ModelKind::kDirectF)->summary.max_relative_error, 1e-8);
  EXPECT_EQ(model.features.window_side_px, 48);
}

// The geometric baseline and the theta correction follow the options: the blur law, whether the
// correction is fitted, and its degree.
TEST(FitCalibration, GeometricAndThetaCorrectionFollowTheOptions) {
  const testing::SyntheticRig rig;
  std::vector<CalibrationSample> samples = rig.Table3();
  for (CalibrationSample& s : samples) {  // a tilted disc: minor = 30 cos^2 u^2 + 1
    const double c = std::cos(s.theta_deg * M_PI / 180.0);
    Features& m = s.measurement;
    m.moment_minor_var_px2 = 1.0 + c * c * (m.moment_major_var_px2 - 1.0);
  }
  FitOptions options = OneModel();
  options.theta_correction_degree = 1;
  options.geometric_blur_varies_with_distance = false;
  const CalibrationModel fixed = Fit(samples, FeatureOptions(), options);
  EXPECT_NEAR(fixed.geometric.alpha_px2, 30.0, 1e-9);
  EXPECT_NEAR(fixed.geometric.beta_px2, 1.0, 1e-9);
  EXPECT_FALSE(fixed.geometric.BlurVariesWithDistance());
  ASSERT_TRUE(fixed.theta_correction.fitted()) << fixed.theta_correction.summary.message;
  EXPECT_EQ(fixed.theta_correction.degree, 1);

  options.geometric_blur_varies_with_distance = true;
  options.fit_theta_correction = false;
  const CalibrationModel varying = Fit(samples, FeatureOptions(), options);
  EXPECT_NEAR(varying.geometric.alpha_px2, 30.0, 1e-8);
  EXPECT_NEAR(varying.geometric.BlurVarPx2(2000.0), 1.0, 1e-8);
  EXPECT_FALSE(varying.theta_correction.fitted());
}

// The calibrated blur is fitted to the usable measurement frames' measured blur at their true
// distance: 0.5 + 0.3 u^2 px^2 (u = 1 m / d) with +-0.01 px^2 of scatter comes back.
TEST(FitCalibration, BlurCalibrationFromTheUsableMeasuredBlur) {
  const testing::SyntheticRig rig;
  std::vector<CalibrationSample> samples = rig.Table3();
  int with_blur = 0;
  for (size_t i = 0; i < samples.size(); ++i) {
    const double u = 1000.0 / samples[i].d_mm;
    samples[i].measurement.blur_var_px2 = 0.5 + 0.3 * u * u + (i % 2 == 0 ? 0.01 : -0.01);
    if (i % 16 == 5) samples[i].measurement.blur_var_px2 = std::nan("");  // not measured
    if (i % 16 == 9) {
      samples[i].measurement.blob_clipped_by_roi = true;  // not usable
      samples[i].measurement.blur_var_px2 = 9.0;
    }
    if (i % 16 != 5 && i % 16 != 9) ++with_blur;
  }
  const CalibrationModel model = Fit(samples, FeatureOptions(), OneModel());
  const BlurCalibration& b = model.blur_calibration;
  EXPECT_EQ(b.frames, with_blur);
  EXPECT_NEAR(b.BlurVarPx2(1500.0), 0.5 + 0.3 / 2.25, 0.01);
  EXPECT_NEAR(b.BlurVarPx2(3000.0), 0.5 + 0.3 / 9.0, 0.01);
  EXPECT_TRUE(b.fitted());
  // Without measured blur, no calibration.
  EXPECT_FALSE(Fit(rig.Table3(), FeatureOptions(), OneModel()).blur_calibration.fitted());
}

TEST(FitCalibration, RefusesInvalidOptionsWithTheReason) {
  const testing::SyntheticRig rig;
  FitOptions none = OneModel();
  none.models.clear();
  try {
    Fit(rig.Table3(), FeatureOptions(), none);
    FAIL() << "no models accepted";
  } catch (const CheckError& e) {
    EXPECT_NE(std::string(e.what()).find("models: nothing to fit"), std::string::npos)
        << e.what();
  }
  FeatureOptions features;
  features.window_side_px = 4;
  try {
    Fit(rig.Table3(), features, OneModel());
    FAIL() << "a 4 px window accepted";
  } catch (const CheckError& e) {
    EXPECT_NE(std::string(e.what()).find("window_side_px"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace irdist
