#include "estimator/model_file.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <fstream>

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
  FeatureOptions features;
  features.roi_policy = RoiPolicy::kThreshold;
  features.window_side_px = 48;
  features.inverse_response.m = {0.0, 0.3, 1.0};
  features.inverse_response.f = {0.0, 0.1 / 3.0, 1.0};
  return Fit(rig.Table3(), features, options);
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
  // Writing again gives the same text.
  EXPECT_EQ(ModelToYaml(back), ModelToYaml(model));
}

TEST(ModelFile, FileHoldsTheFitStatistics) {
  const std::string text = ModelToYaml(SmallModel());
  for (const char* key : {"format_version", "roi_policy", "mean_relative_error",
                          "max_relative_error", "condition_number", "samples", "d_mm", "bias_ma"})
    EXPECT_NE(text.find(key), std::string::npos) << key;
}

TEST(ModelFile, WrongVersionIsRejected) {
  std::string text = ModelToYaml(SmallModel());
  text.replace(text.find("format_version: 1"), 17, "format_version: 9");
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

}  // namespace
}  // namespace irdist
