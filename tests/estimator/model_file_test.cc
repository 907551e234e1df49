#include "estimator/model_file.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <random>

#include "tests/estimator/synthetic.h"

namespace irdist {
namespace {

CalibrationModel SmallModel() {
  const testing::SyntheticRig rig;
  FitOptions options;
  options.models = {ModelKind::kFreeE, ModelKind::kFreeSigma};
  options.sigma_scan_steps = 4;
  options.multi_starts = 1;
  options.max_iterations = 5;
  options.geometric_blur_varies_with_distance = false;  // format 3 content: the old-version tests
  FeatureOptions features;
  features.roi_policy = RoiPolicy::kThreshold;
  features.window_side_px = 48;
  features.inverse_response.m = {0.0, 0.3, 1.0};
  features.inverse_response.f = {0.0, 0.1 / 3.0, 1.0};
  features.moment_method = MomentMethod::kAperture;
  features.aperture_margin_px = 4.25;
  CalibrationModel model = Fit(rig.Table3(), features, options);
  model.geometric.noise_rel_at_1m = 2.0 / 7.0 * 1e-3;
  model.geometric.noise_exponent = 1.0 / 3.0 + 1.0;
  // The synthetic frames carry no minor axis: a hand-made correction (degree 2).
  ThetaCorrection& tc = model.theta_correction;
  tc.degree = 2;
  tc.coefficients = {0.01, 0.97, 0.1 / 3.0, 0.02, -0.003, 1e-17};
  tc.ratio_sq_min = 0.6;
  tc.ratio_sq_max = 0.999;
  tc.d_min_mm = 1499.5;
  tc.d_max_mm = 3000.25;
  tc.summary.termination = FitSummary::Termination::kConverged;
  tc.summary.mean_relative_error = 0.1 / 7.0;
  tc.summary.max_relative_error = 0.5;
  tc.summary.samples = 256;
  return model;
}

// SmallModel with a fitted blur c0_px2 (flat in distance) and its noise, over 40 frames.
CalibrationModel WithBlur(double c0_px2) {
  CalibrationModel model = SmallModel();
  model.blur_calibration.c0_px2 = c0_px2;
  model.blur_calibration.noise_at_1m_px2 = 0.01;
  model.blur_calibration.frames = 40;
  return model;
}

// The reader's refusal of `text` with the line of `key` set to `value`: the error's key and
// message (which must name bad.yaml and its line); {"", "accepted"} when it loads.
struct Refusal {
  std::string key, what;
};
Refusal RefusalWith(const std::string& text, const std::string& key, const std::string& value) {
  std::string bad = text;
  const size_t at = bad.find(key + ": ");
  EXPECT_NE(at, std::string::npos) << key;
  if (at == std::string::npos) return {"", "no such key"};
  bad.replace(at, bad.find('\n', at) - at, key + ": " + value);
  try {
    ModelFromYaml(bad, "bad.yaml");
  } catch (const ModelFileError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.yaml:"), std::string::npos) << e.what();
    return {e.key(), e.what()};
  }
  return {"", "accepted"};
}

bool BitEqual(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

std::string TempPath(const char* name) {
  return std::string(IRDIST_BINARY_DIR) + "/estimator_model_file_test_" + name + ".yaml";
}

TEST(ModelFile, RoundTripIsBitExact) {
  const CalibrationModel model = SmallModel();
  const std::string path = TempPath("roundtrip");
  SaveModel(model, path);
  const CalibrationModel back = LoadModel(path);
  std::remove(path.c_str());
  EXPECT_EQ(back.features.roi_policy, RoiPolicy::kThreshold);
  EXPECT_EQ(back.features.window_side_px, 48);
  ASSERT_EQ(back.features.inverse_response.f.size(), 3u);
  EXPECT_TRUE(BitEqual(back.features.inverse_response.f[1], model.features.inverse_response.f[1]));
  EXPECT_TRUE(BitEqual(back.scaling.df_scale, model.scaling.df_scale));
  EXPECT_TRUE(BitEqual(back.scaling.d_scale, model.scaling.d_scale));
  EXPECT_TRUE(BitEqual(back.ranges.bias_min_ma, model.ranges.bias_min_ma));
  ASSERT_EQ(back.models.size(), model.models.size());
  for (size_t i = 0; i < model.models.size(); ++i) {
    const FittedModel &a = model.models[i], &b = back.models[i];
    EXPECT_EQ(a.kind, b.kind);
    EXPECT_EQ(a.form, b.form);
    EXPECT_TRUE(BitEqual(a.sigma_deg, b.sigma_deg));
    ASSERT_EQ(a.coefficients.size(), b.coefficients.size());
    for (size_t j = 0; j < a.coefficients.size(); ++j)
      EXPECT_TRUE(BitEqual(a.coefficients[j], b.coefficients[j])) << j;
    EXPECT_TRUE(BitEqual(a.summary.mean_relative_error, b.summary.mean_relative_error));
    EXPECT_TRUE(BitEqual(a.summary.max_relative_error, b.summary.max_relative_error));
    EXPECT_TRUE(BitEqual(a.summary.condition_number, b.summary.condition_number));
    EXPECT_EQ(a.summary.samples, b.summary.samples);
  }
  EXPECT_TRUE(BitEqual(back.geometric.alpha_px2, model.geometric.alpha_px2));
  EXPECT_TRUE(BitEqual(back.geometric.noise_rel_at_1m, model.geometric.noise_rel_at_1m));
  EXPECT_TRUE(BitEqual(back.geometric.noise_exponent, model.geometric.noise_exponent));
  EXPECT_EQ(back.features.moment_method, MomentMethod::kAperture);
  EXPECT_TRUE(BitEqual(back.features.aperture_margin_px, 4.25));
  const ThetaCorrection &ta = model.theta_correction, &tb = back.theta_correction;
  ASSERT_TRUE(tb.fitted());
  EXPECT_EQ(tb.degree, 2);
  ASSERT_EQ(tb.coefficients.size(), ta.coefficients.size());
  for (size_t j = 0; j < ta.coefficients.size(); ++j)
    EXPECT_TRUE(BitEqual(ta.coefficients[j], tb.coefficients[j])) << j;
  EXPECT_TRUE(BitEqual(ta.ratio_sq_min, tb.ratio_sq_min));
  EXPECT_TRUE(BitEqual(ta.ratio_sq_max, tb.ratio_sq_max));
  EXPECT_TRUE(BitEqual(ta.d_min_mm, tb.d_min_mm));
  EXPECT_TRUE(BitEqual(ta.d_max_mm, tb.d_max_mm));
  EXPECT_TRUE(BitEqual(ta.summary.mean_relative_error, tb.summary.mean_relative_error));
  EXPECT_EQ(tb.summary.samples, 256);
  // Writing again gives the same text.
  EXPECT_EQ(ModelToYaml(back), ModelToYaml(model));
}

TEST(ModelFile, ProvenanceRoundTripsAndIsOptional) {
  CalibrationModel model = SmallModel();
  EXPECT_EQ(ModelToYaml(model).find("provenance"), std::string::npos);  // unknown: not written
  ModelProvenance& p = model.provenance;
  p.known = true;
  p.rig_name = "virtual";
  p.rig_path = "recipes/rigs/virtual.yaml";
  p.camera_vendor = "Aravis";
  p.camera_model = "Fake";
  p.camera_serial = "IRDV0001";
  p.pixel_format = "Mono12";
  p.bit_depth = 12;
  p.roi_offset_x = 512;
  p.roi_offset_y = 384;
  p.roi_width = 256;
  p.roi_height = 256;
  p.recipe_path = "recipes/table3-calibration.yaml";
  p.calibration_date = "2026-12-01T17:00:00Z";
  p.t_ref_ms = 8.0;
  p.t_meas_ms = {30.0, 33.0, 36.0};
  p.retake_reference = true;
  const std::string text = ModelToYaml(model);
  const CalibrationModel back = ModelFromYaml(text, "p.yaml");
  EXPECT_TRUE(back.provenance.known);
  EXPECT_EQ(back.provenance.camera_serial, "IRDV0001");
  EXPECT_EQ(back.provenance.roi_offset_y, 384);
  EXPECT_EQ(back.provenance.t_meas_ms, p.t_meas_ms);
  EXPECT_TRUE(back.provenance.retake_reference);
  EXPECT_EQ(ModelToYaml(back), text);
  EXPECT_FALSE(ModelFromYaml(ModelToYaml(SmallModel()), "old.yaml").provenance.known);
}

// Format 4: the distance-dependent geometric blur and the health check's calibrated blur round
// trip bit-exactly, and are refused in a file that claims an older format.
TEST(ModelFile, BlurTermsRoundTripAndNeedFormatFour) {
  CalibrationModel model = SmallModel();
  model.geometric.blur_u1_px2 = -0.3 / 7.0;
  model.geometric.blur_u2_px2 = 0.05 / 3.0;
  model.geometric.blur_u3_px2 = -0.02 / 3.0;
  model.blur_calibration.c0_px2 = 0.6 / 7.0;
  model.blur_calibration.c1_px2 = -0.1 / 3.0;
  model.blur_calibration.c2_px2 = 0.2 / 9.0;
  model.blur_calibration.noise_at_1m_px2 = 0.01 / 3.0;
  model.blur_calibration.noise_exponent = 1.25;
  model.blur_calibration.frames = 77;
  const std::string text = ModelToYaml(model);
  const CalibrationModel back = ModelFromYaml(text, "v4.yaml");
  EXPECT_TRUE(BitEqual(back.geometric.blur_u1_px2, model.geometric.blur_u1_px2));
  EXPECT_TRUE(BitEqual(back.geometric.blur_u2_px2, model.geometric.blur_u2_px2));
  EXPECT_TRUE(BitEqual(back.geometric.blur_u3_px2, model.geometric.blur_u3_px2));
  EXPECT_TRUE(BitEqual(back.blur_calibration.c1_px2, model.blur_calibration.c1_px2));
  EXPECT_TRUE(BitEqual(back.blur_calibration.c2_px2, model.blur_calibration.c2_px2));
  EXPECT_TRUE(BitEqual(back.blur_calibration.noise_at_1m_px2,
                       model.blur_calibration.noise_at_1m_px2));
  EXPECT_EQ(back.blur_calibration.frames, 77);
  EXPECT_EQ(ModelToYaml(back), text);
  std::string old = text;
  old.replace(old.find("format_version: 4"), 17, "format_version: 3");
  try {
    ModelFromYaml(old, "v3.yaml");
    FAIL() << "a format 3 file with format 4 keys was accepted";
  } catch (const ModelFileError& e) {
    EXPECT_NE(std::string(e.what()).find("format_version 4"), std::string::npos) << e.what();
  }
}

// The size law's cubic term is optional (absent in files written before it: 0), and refused
// at its line when not finite or without the terms it extends.
TEST(ModelFile, TheSizeLawsCubicTermIsOptionalAndChecked) {
  CalibrationModel model = SmallModel();
  model.geometric.blur_u1_px2 = -0.3 / 7.0;
  model.geometric.blur_u2_px2 = 0.05 / 3.0;
  const std::string text = ModelToYaml(model);
  EXPECT_EQ(text.find("blur_u3_px2"), std::string::npos);
  EXPECT_EQ(ModelFromYaml(text, "quadratic.yaml").geometric.blur_u3_px2, 0.0);
  model.geometric.blur_u3_px2 = 0.01;
  const std::string cubic = ModelToYaml(model);
  const size_t at = cubic.find("blur_u3_px2: ");
  ASSERT_NE(at, std::string::npos);
  std::string bad = cubic;
  bad.replace(at, bad.find('\n', at) - at, "blur_u3_px2: .nan");
  try {
    ModelFromYaml(bad, "nan.yaml");
    FAIL() << "a NaN cubic term was accepted";
  } catch (const ModelFileError& e) {
    EXPECT_NE(std::string(e.what()).find("nan.yaml:"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("blur_u3_px2"), std::string::npos) << e.what();
  }
  std::string alone = cubic;
  for (const char* key : {"blur_u1_px2: ", "blur_u2_px2: "}) {
    const size_t line = alone.rfind('\n', alone.find(key)) + 1;
    alone.erase(line, alone.find('\n', line) - line + 1);
  }
  try {
    ModelFromYaml(alone, "alone.yaml");
    FAIL() << "a cubic term without the terms it extends was accepted";
  } catch (const ModelFileError& e) {
    EXPECT_NE(std::string(e.what()).find("blur_u1_px2"), std::string::npos) << e.what();
  }
}

// The size's tilt term round trips bit-exact; absent, none; its knots and values are checked
// at their line (one value per knot, knots increasing in [0, 90), values within the blob fit's
// blur corrections' bound).
TEST(ModelFile, TheSizesTiltTermRoundTripsAndIsChecked) {
  CalibrationModel model = SmallModel();
  EXPECT_EQ(ModelToYaml(model).find("tilt_"), std::string::npos);
  EXPECT_TRUE(ModelFromYaml(ModelToYaml(model), "none.yaml").geometric.tilt_theta_deg.empty());
  model.geometric.tilt_theta_deg = {0.0, 10.0, 20.0, 35.0};
  model.geometric.tilt_var_px2 = {0.0, 0.1 / 3.0, -0.2 / 7.0, 0.0};
  const std::string text = ModelToYaml(model);
  const CalibrationModel back = ModelFromYaml(text, "tilt.yaml");
  EXPECT_EQ(back.geometric.tilt_theta_deg, model.geometric.tilt_theta_deg);
  EXPECT_EQ(back.geometric.tilt_var_px2, model.geometric.tilt_var_px2);
  const auto refused = [&text](const std::string& key, const std::string& value) {
    return RefusalWith(text, key, value).what;
  };
  EXPECT_NE(refused("tilt_var_px2", "[0, 0.1]").find("one value per knot"), std::string::npos);
  EXPECT_NE(refused("tilt_theta_deg", "[0, 20, 10, 35]").find("increasing"), std::string::npos);
  EXPECT_NE(refused("tilt_theta_deg", "[0, 10, 20, 95]").find("[0, 90)"), std::string::npos);
  EXPECT_NE(refused("tilt_var_px2", "[0, 40, 0, 0]").find("tilt_var_px2[1]"), std::string::npos);
}

// The blur's split (the crosstalk's variance and kernel shape) round trips; absent, the
// whole blur is the optics'; out of range, refused at its line.
TEST(ModelFile, CrosstalkSplitRoundTripsAndIsChecked) {
  CalibrationModel model = WithBlur(0.9);
  EXPECT_EQ(ModelToYaml(model).find("crosstalk"), std::string::npos);  // none: no key
  EXPECT_EQ(ModelFromYaml(ModelToYaml(model), "none.yaml").blur_calibration.crosstalk_var_px2, 0.0);
  model.blur_calibration.crosstalk_var_px2 = 0.64 / 3.0;
  model.blur_calibration.crosstalk_lattice_share = 0.7 / 3.0;
  const std::string text = ModelToYaml(model);
  const CalibrationModel back = ModelFromYaml(text, "split.yaml");
  EXPECT_TRUE(BitEqual(back.blur_calibration.crosstalk_var_px2, 0.64 / 3.0));
  EXPECT_TRUE(BitEqual(back.blur_calibration.crosstalk_lattice_share, 0.7 / 3.0));
  EXPECT_EQ(ModelToYaml(back), text);
  EXPECT_NE(RefusalWith(text, "crosstalk_lattice_share", "1.5").what.find("[0, 1]"),
            std::string::npos);
}

// The blob fit's blur offset round trips; absent, zero; out of range, refused at its
// line with the range.
TEST(ModelFile, FitBlurOffsetRoundTripsAndIsChecked) {
  CalibrationModel model = WithBlur(0.9);
  EXPECT_EQ(ModelToYaml(model).find("fit_offset"), std::string::npos);
  model.blur_calibration.fit_offset_px2 = -0.07 / 3.0;
  model.blur_calibration.fit_offset_u_px2 = 0.09 / 7.0;
  const std::string text = ModelToYaml(model);
  const CalibrationModel back = ModelFromYaml(text, "offset.yaml");
  EXPECT_TRUE(BitEqual(back.blur_calibration.fit_offset_px2, -0.07 / 3.0));
  EXPECT_TRUE(BitEqual(back.blur_calibration.fit_offset_u_px2, 0.09 / 7.0));
  EXPECT_NEAR(back.blur_calibration.FitBlurVarPx2(2000.0),
              back.blur_calibration.BlurVarPx2(2000.0) - 0.07 / 3.0 + 0.5 * 0.09 / 7.0, 1e-15);
  const Refusal negative = RefusalWith(text, "fit_offset_u_px2", "-3");  // the blur below 0
  EXPECT_EQ(negative.key, "blur_calibration.fit_offset_u_px2") << negative.what;
  EXPECT_NE(negative.what.find("(0, 16] px^2"), std::string::npos) << negative.what;
}

// The offset's bend (u^2) round trips; absent (files before it, and a straight line), zero; a
// bend that takes the fit's blur below 0 within the calibrated range is refused at its key.
TEST(ModelFile, FitBlurOffsetsBendRoundTripsAndIsChecked) {
  CalibrationModel model = WithBlur(0.9);
  model.blur_calibration.fit_offset_px2 = -0.07 / 3.0;
  EXPECT_EQ(ModelToYaml(model).find("fit_offset_u2_px2"), std::string::npos);
  model.blur_calibration.fit_offset_u2_px2 = 0.11 / 3.0;
  const std::string text = ModelToYaml(model);
  const CalibrationModel back = ModelFromYaml(text, "bend.yaml");
  EXPECT_TRUE(BitEqual(back.blur_calibration.fit_offset_u2_px2, 0.11 / 3.0));
  EXPECT_NEAR(back.blur_calibration.FitBlurVarPx2(2000.0),
              back.blur_calibration.BlurVarPx2(2000.0) - 0.07 / 3.0 + 0.25 * 0.11 / 3.0, 1e-15);
  const Refusal negative = RefusalWith(text, "fit_offset_u2_px2", "-9");
  EXPECT_EQ(negative.key, "blur_calibration.fit_offset_u_px2") << negative.what;
  const Refusal huge = RefusalWith(text, "fit_offset_u2_px2", "1e9");
  EXPECT_EQ(huge.key, "blur_calibration.fit_offset_u2_px2") << huge.what;
}

// The PSF's anisotropy round trips; absent (older files), a round PSF.
TEST(ModelFile, PsfAnisotropyRoundTripsAndIsOptional) {
  CalibrationModel model = WithBlur(0.9);
  EXPECT_EQ(ModelToYaml(model).find("psf_aniso"), std::string::npos);
  model.blur_calibration.psf_aniso_c_px2 = 0.153 / 3.0;
  model.blur_calibration.psf_aniso_s_px2 = -0.265 / 7.0;
  const CalibrationModel back = ModelFromYaml(ModelToYaml(model), "astigmatic.yaml");
  EXPECT_TRUE(BitEqual(back.blur_calibration.psf_aniso_c_px2, 0.153 / 3.0));
  EXPECT_TRUE(BitEqual(back.blur_calibration.psf_aniso_s_px2, -0.265 / 7.0));
  const CalibrationModel round = ModelFromYaml(ModelToYaml(WithBlur(0.9)), "round.yaml");
  EXPECT_EQ(round.blur_calibration.psf_aniso_c_px2, 0.0);
  EXPECT_EQ(round.blur_calibration.psf_aniso_s_px2, 0.0);
}

// The optics' edge beyond a Gaussian's (its excess kurtosis) round trips; absent (older files and
// a Gaussian edge), 0; out of its range, refused at its line with the range.
TEST(ModelFile, OpticsExcessRoundTripsAndIsChecked) {
  CalibrationModel model = WithBlur(0.9);
  EXPECT_EQ(ModelToYaml(model).find("optics_excess"), std::string::npos);
  EXPECT_EQ(ModelFromYaml(ModelToYaml(model), "gauss.yaml").blur_calibration.optics_excess, 0.0);
  model.blur_calibration.optics_excess = -2.1 / 3.0;
  const std::string text = ModelToYaml(model);
  const CalibrationModel back = ModelFromYaml(text, "defocus.yaml");
  EXPECT_TRUE(BitEqual(back.blur_calibration.optics_excess, -2.1 / 3.0));
  EXPECT_EQ(ModelToYaml(back), text);
  const Refusal beyond = RefusalWith(text, "optics_excess", "7");
  EXPECT_EQ(beyond.key, "blur_calibration.optics_excess") << beyond.what;
  EXPECT_NE(beyond.what.find("[-3, 4]"), std::string::npos) << beyond.what;
}

// The edge correction (estimator/edge_correction.h) round trips exactly (its knots are whole
// 1e-6, which the file's six digits hold); absent (older files and every lens the fit's edge
// describes), none; a table of another length, or a knot outside its bound, is refused at its
// line with the fix.
TEST(ModelFile, EdgeCorrectionRoundTripsAndIsChecked) {
  CalibrationModel model = WithBlur(0.9);
  EXPECT_EQ(ModelToYaml(model).find("edge_correction"), std::string::npos);
  EXPECT_TRUE(
      ModelFromYaml(ModelToYaml(model), "none.yaml").blur_calibration.edge_correction.empty());
  std::vector<double>& table = model.blur_calibration.edge_correction;
  for (int k = 0; k < kEdgeCorrectionKnots; ++k) {
    table.push_back(std::round(0.0123457 * std::sin(0.37 * k) * 1e6) / 1e6);
  }
  table.front() = table.back() = 0.0;
  const std::string text = ModelToYaml(model);
  const CalibrationModel back = ModelFromYaml(text, "airy.yaml");
  ASSERT_EQ(back.blur_calibration.edge_correction.size(), table.size());
  for (size_t k = 0; k < table.size(); ++k) {
    EXPECT_TRUE(BitEqual(back.blur_calibration.edge_correction[k], table[k])) << "knot " << k;
  }
  EXPECT_EQ(ModelToYaml(back), text);
  const Refusal shorter = RefusalWith(text, "edge_correction", "[0, 0.01, 0]");
  EXPECT_EQ(shorter.key, "blur_calibration.edge_correction") << shorter.what;
  EXPECT_NE(shorter.what.find("expected 101 numbers"), std::string::npos) << shorter.what;
  std::string beyond = "[0";
  for (int k = 1; k < kEdgeCorrectionKnots; ++k) beyond += k == 50 ? ", 0.9" : ", 0";
  const Refusal large = RefusalWith(text, "edge_correction", beyond + "]");
  EXPECT_EQ(large.key, "blur_calibration.edge_correction[50]") << large.what;
  EXPECT_NE(large.what.find("[-0.5, 0.5]"), std::string::npos) << large.what;
}

// A fitness figure (estimator/fitness.h) with two named poses, one failing.
CalibrationFitness SomeFitness() {
  CalibrationFitness f;
  f.assessed = true;
  f.passed = false;
  f.poses = 64;
  f.dof = 180;
  f.reduced_chi2 = 7.0 / 3.0;
  f.chi2 = f.reduced_chi2 * f.dof;
  f.limit = 1.0 + 1.0 / 7.0;
  f.pose_limit = 25.0 / 3.0;
  f.tail_probability = 1e-3;
  f.size_floor = 0.004;
  f.difference_floor = 0.005;
  f.poses_over = 17;
  f.cause = "an optic outside the model's family: 17 of 64 poses miss";
  f.worst.push_back({{3000.0, 35.0, -0.5, 475.0}, 90.0 / 7.0, 4, 1.0 / 3.0, "minor", -2.0 / 3.0});
  f.worst.push_back({{1500.0, 0.0, 0.0, 500.0}, 11.0 / 3.0, 3, 2.5, "dE", 0.125});
  return f;
}

// The fitness round-trips bit for bit; a model without it (every model before it)
// still loads, not assessed.
TEST(ModelFile, FitnessRoundTripsAndIsOptional) {
  CalibrationModel model = WithBlur(0.9);
  EXPECT_EQ(ModelToYaml(model).find("fitness"), std::string::npos);
  EXPECT_FALSE(ModelFromYaml(ModelToYaml(model), "old.yaml").fitness.assessed);
  model.fitness = SomeFitness();
  const CalibrationModel back = ModelFromYaml(ModelToYaml(model), "fitness.yaml");
  const CalibrationFitness& f = back.fitness;
  ASSERT_TRUE(f.assessed);
  EXPECT_FALSE(f.passed);
  EXPECT_TRUE(BitEqual(f.reduced_chi2, 7.0 / 3.0));
  EXPECT_TRUE(BitEqual(f.limit, 1.0 + 1.0 / 7.0));
  EXPECT_TRUE(BitEqual(f.pose_limit, 25.0 / 3.0));
  EXPECT_EQ(f.dof, 180);
  EXPECT_EQ(f.poses, 64);
  EXPECT_EQ(f.poses_over, 17);
  EXPECT_EQ(f.difference_floor, 0.005);
  EXPECT_EQ(f.cause, SomeFitness().cause);
  ASSERT_EQ(f.worst.size(), 2u);
  EXPECT_EQ(f.worst[0].pose.tilt_deg, -0.5);
  EXPECT_TRUE(BitEqual(f.worst[0].chi2, 90.0 / 7.0));
  EXPECT_TRUE(BitEqual(f.worst[0].worst_residual_percent, -2.0 / 3.0));
  EXPECT_EQ(f.worst[1].worst_channel, "dE");
  EXPECT_EQ(f.worst[1].channels, 3);
  EXPECT_EQ(ModelToYaml(back), ModelToYaml(model));
}

// A fitness number outside its bound (base/bounds.h) is refused at its key and line.
TEST(ModelFile, FitnessOutsideItsBoundsIsRefusedAtItsLine) {
  CalibrationModel model = WithBlur(0.9);
  model.fitness = SomeFitness();
  std::string text = ModelToYaml(model);
  const size_t at = text.find("reduced_chi2: ");
  ASSERT_NE(at, std::string::npos);
  text.replace(at, text.find('\n', at) - at, "reduced_chi2: -1");
  try {
    ModelFromYaml(text, "bad.yaml");
    FAIL() << "a negative chi-square was accepted";
  } catch (const ModelFileError& e) {
    EXPECT_EQ(e.key(), "fitness.reduced_chi2");
    EXPECT_NE(std::string(e.what()).find("bad.yaml:"), std::string::npos) << e.what();
  }
  model.fitness.worst[1].pose.bias_ma = 1e6;
  try {
    SaveModel(model, TempPath("fitness_outside"));
    ADD_FAILURE() << "written";
  } catch (const ModelFileError& e) {
    EXPECT_EQ(e.key(), "fitness.worst_poses[1].bias_ma");
  }
}

// Regression: a defocused lens's fit (fit_offset_u_px2 -0.573 on a blur of about 1 px^2)
// is written and read back (it was refused by every reader, outside [-0.5, 0.5]).
TEST(ModelFile, ADefocusedLensModelIsWrittenAndRead) {
  CalibrationModel model = WithBlur(1.2);
  model.blur_calibration.fit_offset_u_px2 = -0.573;
  const std::string path = TempPath("defocus");
  SaveModel(model, path);
  const CalibrationModel back = LoadModel(path);
  std::remove(path.c_str());
  EXPECT_EQ(back.blur_calibration.fit_offset_u_px2, -0.573);
}

// Regression: a fit that lands outside the bounds is refused by the writer naming the
// parameter and why; no file is left for the next command to reject.
TEST(ModelFile, AFitOutsideTheBoundsIsNotWritten) {
  CalibrationModel model = WithBlur(0.2);
  model.blur_calibration.fit_offset_u_px2 = -0.573;
  const std::string path = TempPath("outside");
  std::remove(path.c_str());
  try {
    SaveModel(model, path);
    ADD_FAILURE() << "written";
  } catch (const ModelFileError& e) {
    EXPECT_EQ(e.key(), "blur_calibration.fit_offset_u_px2");
    EXPECT_NE(std::string(e.what()).find("not written"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("a variance is > 0"), std::string::npos) << e.what();
  }
  struct stat st;
  EXPECT_NE(stat(path.c_str(), &st), 0) << "a file was left at " << path;
}

// As a property: whatever a fit lands on (blurs, offsets, noise, exposures and
// windows drawn over and beyond their bounds), SaveModel either writes a file that LoadModel (the
// reader of playback, measure and Python) accepts, identical when written again, or refuses with
// the parameter named and leaves no file.
TEST(ModelFile, EveryModelTheWriterWritesTheReaderAccepts) {
  std::mt19937_64 random(38);
  auto uniform = [&random](double lo, double hi) {
    return std::uniform_real_distribution<double>(lo, hi)(random);
  };
  const std::string path = TempPath("property");
  int written = 0, refused = 0;
  const CalibrationModel fitted = WithBlur(1.0);
  for (int i = 0; i < 200; ++i) {
    CalibrationModel model = fitted;
    BlurCalibration& b = model.blur_calibration;
    b.c0_px2 = uniform(-1.0, 20.0);
    b.c1_px2 = uniform(-2.0, 2.0);
    b.c2_px2 = uniform(-1.0, 1.0);
    b.fit_offset_px2 = uniform(-2.0, 2.0);
    b.fit_offset_u_px2 = uniform(-2.0, 2.0);
    b.noise_exponent = uniform(-12.0, 12.0);
    ModelProvenance& p = model.provenance;
    p.known = true;
    p.pixel_format = "Mono12";
    p.bit_depth = 12;
    p.roi_width = p.roi_height = 256;
    p.t_ref_ms = uniform(-1.0, 20.0);
    p.t_meas_ms = {uniform(0.0, 60.0), uniform(0.0, 1.2e5)};
    model.features.window_side_px = i % 10 == 0 ? 512 : 48;
    std::remove(path.c_str());
    try {
      SaveModel(model, path);
    } catch (const ModelFileError& e) {
      EXPECT_FALSE(e.key().empty()) << e.what();
      struct stat st;
      EXPECT_NE(stat(path.c_str(), &st), 0) << "a refused model left a file: " << e.what();
      ++refused;
      continue;
    }
    ++written;
    try {
      EXPECT_EQ(ModelToYaml(LoadModel(path)), ModelToYaml(model));
    } catch (const ModelFileError& e) {
      ADD_FAILURE() << "written, then refused by the reader: " << e.what();
    }
  }
  std::remove(path.c_str());
  EXPECT_GT(written, 20) << refused;  // both sides of the bounds are drawn
  EXPECT_GT(refused, 20);
}

// Regression: blur_var_px2 [-5, 0, 0] and [1e300, 0, 0] were loaded and used; refused at the
// key's line now.
TEST(ModelFile, ABlurThatIsNoVarianceIsRefusedAtItsLine) {
  CalibrationModel model = WithBlur(0.9);
  const std::string good = ModelToYaml(model);
  const size_t at = good.find("blur_var_px2: ");
  ASSERT_NE(at, std::string::npos);
  const int line = 1 + static_cast<int>(std::count(good.begin(), good.begin() + at, '\n'));
  for (const char* bad : {"blur_var_px2: [-5, 0, 0]", "blur_var_px2: [1e300, 0, 0]"}) {
    SCOPED_TRACE(bad);
    std::string text = good;
    text.replace(at, text.find('\n', at) - at, bad);
    try {
      ModelFromYaml(text, "m.yaml");
      ADD_FAILURE() << "accepted";
    } catch (const ModelFileError& e) {
      EXPECT_EQ(e.key(), "blur_calibration.blur_var_px2");
      EXPECT_EQ(e.line(), line);
    }
  }
}

TEST(ModelFile, FileHoldsTheFitStatistics) {
  const std::string text = ModelToYaml(SmallModel());
  for (const char* key : {"format_version", "roi_policy", "mean_relative_error",
                          "max_relative_error", "condition_number", "samples", "d_mm", "bias_ma"})
    EXPECT_NE(text.find(key), std::string::npos) << key;
}

TEST(ModelFile, VersionOneFileLoadsAsThresholdMomentsWithoutThetaCorrection) {
  // A version 1 file: no moment_method, aperture_margin_px or theta_correction keys.
  CalibrationModel v1 = SmallModel();
  v1.features.moment_method = MomentMethod::kThreshold;
  v1.features.aperture_margin_px = FeatureOptions().aperture_margin_px;
  v1.theta_correction = ThetaCorrection();
  std::string text = ModelToYaml(v1);
  ASSERT_EQ(text.find("theta_correction"), std::string::npos);
  text.replace(text.find("format_version: 4"), 17, "format_version: 1");
  for (const char* key : {"moment_method", "aperture_margin_px", "response_scope"}) {
    const size_t at = text.find(std::string("  ") + key + ":");
    ASSERT_NE(at, std::string::npos) << key;
    text.erase(at, text.find('\n', at) - at + 1);
  }
  const CalibrationModel back = ModelFromYaml(text, "v1.yaml");
  EXPECT_EQ(back.features.moment_method, MomentMethod::kThreshold);
  EXPECT_EQ(back.features.aperture_margin_px, FeatureOptions().aperture_margin_px);
  EXPECT_FALSE(back.theta_correction.fitted());
  EXPECT_EQ(back.features.window_side_px, 48);
}

TEST(ModelFile, ResponseScopeRoundTripsAndOldVersionsMeanERelOnly) {
  CalibrationModel model = SmallModel();
  model.features.response_scope = ResponseScope::kAllPixels;
  const std::string text = ModelToYaml(model);
  EXPECT_NE(text.find("format_version: 4"), std::string::npos);
  EXPECT_NE(text.find("response_scope: all_pixels"), std::string::npos);
  const CalibrationModel back = ModelFromYaml(text, "v3.yaml");
  EXPECT_EQ(back.features.response_scope, ResponseScope::kAllPixels);
  ASSERT_EQ(back.features.inverse_response.f.size(), 3u);
  EXPECT_EQ(ModelToYaml(back), text);
  // Versions 1 and 2 have no response_scope: the curve entered E_rel only.
  for (const char* version : {"format_version: 2", "format_version: 1"}) {
    std::string old = text;
    old.replace(old.find("format_version: 4"), 17, version);
    const size_t at = old.find("  response_scope:");
    std::string with_key = old;
    old.erase(at, old.find('\n', at) - at + 1);
    const CalibrationModel loaded = ModelFromYaml(old, "old.yaml");
    EXPECT_EQ(loaded.features.response_scope, ResponseScope::kERelOnly) << version;
    EXPECT_TRUE(BitEqual(loaded.features.inverse_response.f[1], model.features.inverse_response.f[1]));
    // The key in an older file is an error naming it.
    try {
      ModelFromYaml(with_key, "old.yaml");
      FAIL() << "accepted response_scope in " << version;
    } catch (const ModelFileError& e) {
      EXPECT_EQ(e.key(), "features.response_scope");
      EXPECT_GT(e.line(), 1);
    }
  }
  std::string bad = text;
  bad.replace(bad.find("response_scope: all_pixels"), 26, "response_scope: some_pixels");
  EXPECT_THROW(ModelFromYaml(bad, "m.yaml"), ModelFileError);
}

// features.blob_fit: absent = the blob fit (estimation default); false round-trips (moments path).
TEST(ModelFile, BlobFitFlagRoundTripsAndDefaultsToTheFit) {
  CalibrationModel model = SmallModel();
  const std::string default_text = ModelToYaml(model);
  EXPECT_EQ(default_text.find("blob_fit"), std::string::npos);
  EXPECT_TRUE(ModelFromYaml(default_text, "m.yaml").features.blob_fit);
  model.features.blob_fit = false;
  const std::string text = ModelToYaml(model);
  EXPECT_NE(text.find("blob_fit: false"), std::string::npos);
  const CalibrationModel back = ModelFromYaml(text, "m.yaml");
  EXPECT_FALSE(back.features.blob_fit);
  EXPECT_EQ(ModelToYaml(back), text);
  std::string bad = text;
  bad.replace(bad.find("blob_fit: false"), 15, "blob_fit: maybe");
  EXPECT_THROW(ModelFromYaml(bad, "m.yaml"), Error);
}

// features.defect_map (the calibration's defect map, estimator/defect_map_file.h): absent = none,
// round-trips, and a bad pixel names its key.
TEST(ModelFile, DefectMapRoundTripsAndIsOptional) {
  CalibrationModel model = SmallModel();
  EXPECT_EQ(ModelToYaml(model).find("defect_map"), std::string::npos);
  EXPECT_TRUE(ModelFromYaml(ModelToYaml(model), "m.yaml").features.scene.defect_map.empty());
  model.features.scene.defect_map.roi = cv::Rect(320, 256, 640, 512);
  model.features.scene.defect_map.sensor_px = {{330, 300}, {331, 300}, {900, 700}};
  const std::string text = ModelToYaml(model);
  const CalibrationModel back = ModelFromYaml(text, "m.yaml");
  EXPECT_EQ(back.features.scene.defect_map.sensor_px, model.features.scene.defect_map.sensor_px);
  EXPECT_EQ(back.features.scene.defect_map.roi, model.features.scene.defect_map.roi);
  EXPECT_EQ(ModelToYaml(back), text);
  std::string bad = text;
  bad.replace(bad.find("[331, 300]"), 10, "[331, -3]");
  try {
    ModelFromYaml(bad, "m.yaml");
    FAIL() << "accepted a negative pixel";
  } catch (const ModelFileError& e) {
    EXPECT_EQ(e.key(), "features.defect_map.pixels[1]");
  }
}

TEST(ModelFile, BadThetaCorrectionNamesTheKey) {
  std::string text = ModelToYaml(SmallModel());
  const size_t section = text.find("theta_correction:");
  ASSERT_NE(section, std::string::npos);
  const size_t at = text.find("coefficients: [", section);
  text.replace(at, 15, "coefficients: [1, ");  // 7 coefficients for degree 2
  try {
    ModelFromYaml(text, "m.yaml");
    FAIL() << "accepted a wrong number of coefficients";
  } catch (const ModelFileError& e) {
    EXPECT_EQ(e.key(), "theta_correction.coefficients");
    EXPECT_GT(e.line(), 1);
  }
  std::string bad_method = ModelToYaml(SmallModel());
  const size_t m = bad_method.find("moment_method: aperture");
  ASSERT_NE(m, std::string::npos);
  bad_method.replace(m, 23, "moment_method: banana");
  try {
    ModelFromYaml(bad_method, "m.yaml");
    FAIL() << "accepted an unknown moment method";
  } catch (const ModelFileError& e) {
    EXPECT_EQ(e.key(), "features.moment_method");
  }
}

TEST(ModelFile, WrongVersionIsRejected) {
  std::string text = ModelToYaml(SmallModel());
  text.replace(text.find("format_version: 4"), 17, "format_version: 9");
  try {
    ModelFromYaml(text, "m.yaml");
    FAIL() << "accepted a wrong version";
  } catch (const ModelFileError& e) {
    EXPECT_EQ(e.key(), "format_version");
    EXPECT_EQ(e.line(), 1);
    EXPECT_NE(std::string(e.what()).find("m.yaml:1"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("format_version"), std::string::npos) << e.what();
  }
}

TEST(ModelFile, CorruptValuesNameTheKeyAndLine) {
  const std::string good = ModelToYaml(SmallModel());
  {
    std::string text = good;
    const size_t at = text.find("d_scale: ");
    text.replace(at, text.find('\n', at) - at, "d_scale: banana");
    try {
      ModelFromYaml(text, "m.yaml");
      FAIL();
    } catch (const ModelFileError& e) {
      EXPECT_EQ(e.key(), "scaling.d_scale");
      EXPECT_GT(e.line(), 1);
      EXPECT_NE(std::string(e.what()).find("scaling.d_scale"), std::string::npos);
    }
  }
  {
    std::string text = good;
    const size_t at = text.find("coefficients: [");
    text.replace(at, 15, "coefficients: [1, ");  // one coefficient too many
    try {
      ModelFromYaml(text, "m.yaml");
      FAIL();
    } catch (const ModelFileError& e) {
      EXPECT_EQ(e.key(), "models[0].coefficients");
    }
  }
  {
    std::string text = good;
    text.erase(text.find("ranges:"), 7).insert(0, "");
    EXPECT_THROW(ModelFromYaml(text, "m.yaml"), ModelFileError);
  }
  EXPECT_THROW(ModelFromYaml("format_version: [1\n", "m.yaml"), ModelFileError);
  EXPECT_THROW(LoadModel("/nonexistent/model.yaml"), ModelFileError);
}


// The text with the first number after `key: [` (a flow list) replaced by `value`.
std::string WithFirstListValue(std::string text, const std::string& key, const std::string& value) {
  const size_t at = text.find(key + ": [") + key.size() + 3;
  text.replace(at, text.find_first_of(",]", at) - at, value);
  return text;
}

TEST(ModelFileSafety, NanOrInfNumbersAreRefusedWithFileAndLine) {
  const std::string good = ModelToYaml(SmallModel());
  for (const std::string bad : {".nan", ".inf", "-.inf"}) {
    try {
      ModelFromYaml(WithFirstListValue(good, "coefficients", bad), "m.yaml");
      FAIL() << "a model with a " << bad << " coefficient was accepted";
    } catch (const ModelFileError& e) {
      EXPECT_EQ(e.key(), "models[0].coefficients[0]");
      EXPECT_GT(e.line(), 1);
      EXPECT_NE(std::string(e.what()).find("m.yaml:"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("not a finite number"), std::string::npos) << e.what();
    }
  }
  std::string text = good;
  const size_t at = text.find("alpha_px2: ");
  text.replace(at, text.find('\n', at) - at, "alpha_px2: .nan");
  EXPECT_THROW(ModelFromYaml(text, "m.yaml"), ModelFileError);
  EXPECT_THROW(ModelFromYaml(WithFirstListValue(good, "d_mm", ".inf"), "m.yaml"), ModelFileError);
}

TEST(ModelFileSafety, MissingModelBlockNamesTheFileNotTheEstimator) {
  CalibrationModel model = SmallModel();
  model.models.erase(model.models.begin() + 1);  // only free_e left
  try {
    ModelFromYaml(ModelToYaml(model), "lab/model.yaml");
    FAIL() << "a model without free_sigma was accepted";
  } catch (const ModelFileError& e) {
    EXPECT_EQ(e.path(), "lab/model.yaml");
    EXPECT_NE(std::string(e.what()).find("no free_sigma model"), std::string::npos) << e.what();
  }
  std::string text = ModelToYaml(SmallModel());
  text.erase(text.find("geometric:"));
  EXPECT_THROW(ModelFromYaml(text, "m.yaml"), ModelFileError);
}

TEST(ModelFileSafety, MisspeltKeyIsAnErrorNotADefault) {
  std::string text = ModelToYaml(SmallModel());
  text.replace(text.find("psf_sigma_px"), 12, "psf_sigma_pz");
  try {
    ModelFromYaml(text, "m.yaml");
    FAIL();
  } catch (const ModelFileError& e) {
    EXPECT_NE(std::string(e.what()).find("unknown key"), std::string::npos) << e.what();
    EXPECT_GT(e.line(), 1);
  }
}

// Regression: t_ref_ms 1e300 and t_meas_ms [-30, 0] in a provenance passed; refused naming
// the key (an element of a list by its index) at its line.
TEST(ModelFileSafety, ProvenanceExposuresOutsideTheBoundsAreRefused) {
  CalibrationModel model = SmallModel();
  ModelProvenance& p = model.provenance;
  p.known = true;
  p.pixel_format = "Mono12";
  p.bit_depth = 12;
  p.t_ref_ms = 8.0;
  p.t_meas_ms = {30.0, 32.0};
  const std::string good = ModelToYaml(model);
  const struct {
    const char* from;
    const char* to;
    const char* key;
  } cases[] = {{"t_ref_ms: 8", "t_ref_ms: 1e300", "provenance.t_ref_ms"},
               {"t_meas_ms: [30, 32]", "t_meas_ms: [-30, 0]", "provenance.t_meas_ms[0]"},
               {"t_meas_ms: [30, 32]", "t_meas_ms: [30, 1e6]", "provenance.t_meas_ms[1]"}};
  for (const auto& c : cases) {
    SCOPED_TRACE(c.to);
    std::string text = good;
    const size_t at = text.find(c.from);
    ASSERT_NE(at, std::string::npos) << text;
    text.replace(at, std::string(c.from).size(), c.to);
    const int line = 1 + static_cast<int>(std::count(text.begin(), text.begin() + at, '\n'));
    try {
      ModelFromYaml(text, "m.yaml");
      ADD_FAILURE() << "accepted";
    } catch (const ModelFileError& e) {
      EXPECT_EQ(e.key(), c.key);
      EXPECT_EQ(e.line(), line);
      EXPECT_NE(std::string(e.what()).find("(0, 100000] ms"), std::string::npos) << e.what();
    }
  }
}

// A provenance whose roi_px or bit_depth no camera has: refused naming the key, before any cast
// (roi_px 1e300 was undefined behaviour).
TEST(ModelFileSafety, ProvenanceRoiAndBitDepthOutsideAnyCameraAreRefused) {
  CalibrationModel model = SmallModel();
  ModelProvenance& p = model.provenance;
  p.known = true;
  p.pixel_format = "Mono12";
  p.bit_depth = 12;
  p.roi_offset_x = 512;
  p.roi_offset_y = 384;
  p.roi_width = 256;
  p.roi_height = 256;
  p.t_ref_ms = 8.0;
  p.t_meas_ms = {30.0};
  const std::string good = ModelToYaml(model);
  EXPECT_EQ(ModelFromYaml(good, "m.yaml").provenance.roi_width, 256);
  const std::string roi = "roi_px: [512, 384, 256, 256]";
  ASSERT_NE(good.find(roi), std::string::npos) << good;
  for (const std::string bad : {"roi_px: [1e300, 384, 256, 256]", "roi_px: [-5, 384, 256, 256]",
                                "roi_px: [512, 384, -256, 256]", "roi_px: [512, 384, 256.5, 256]",
                                "roi_px: [512, 384, 0, 256]"}) {
    SCOPED_TRACE(bad);
    std::string text = good;
    text.replace(text.find(roi), roi.size(), bad);
    try {
      ModelFromYaml(text, "m.yaml");
      ADD_FAILURE() << "accepted";
    } catch (const ModelFileError& e) {
      EXPECT_EQ(e.key(), "provenance.roi_px");
      EXPECT_GT(e.line(), 1);
      EXPECT_NE(std::string(e.what()).find("[0, 1048576]"), std::string::npos) << e.what();
    }
  }
  for (const std::string depth : {"-7", "0", "17", "2147483647"}) {
    SCOPED_TRACE(depth);
    std::string text = good;
    const size_t at = text.find("bit_depth: 12");
    text.replace(at, 13, "bit_depth: " + depth);
    try {
      ModelFromYaml(text, "m.yaml");
      ADD_FAILURE() << "accepted";
    } catch (const ModelFileError& e) {
      EXPECT_EQ(e.key(), "provenance.bit_depth");
      EXPECT_NE(std::string(e.what()).find("1..16"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace irdist

// A FIFO given as the model path is refused at once, naming the file (a read would block forever).
TEST(ModelFileSafety, FifoInPlaceOfAModelIsRefusedWithoutBlocking) {
  const std::string path = ::testing::TempDir() + "model_fifo_" + std::to_string(::getpid());
  ::unlink(path.c_str());
  ASSERT_EQ(::mkfifo(path.c_str(), 0600), 0);
  try {
    irdist::LoadModel(path);
    ADD_FAILURE() << "a FIFO was read as a model";
  } catch (const irdist::ModelFileError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("not a regular file"), std::string::npos) << e.what();
  }
  ::unlink(path.c_str());
}
