// The warnings about a model before it is used (model fitness, the optics fingerprint). The
// estimates themselves are checked end to end by tests/app/runs/playback_command_test.cc,
// tests/app/live/measure_test.cc and tests/integration/calibrate_validate_test.cc.
#include "app/processing/bracket_estimates.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace irdist {
namespace {

// Model fitness: each weakness of a model is a named warning, none for a complete one.
TEST(ModelFitness, NamesABlankSerialAMissingProvenanceAndNoFingerprint) {
  CalibrationModel model;
  const auto names = [](const std::vector<std::string>& warnings) {
    std::string all;
    for (const std::string& w : warnings) all += w + "\n";
    return all;
  };
  std::string text = names(ModelFitnessWarnings(model, "m.yaml"));
  EXPECT_NE(text.find("model fitness (no_provenance): m.yaml"), std::string::npos) << text;
  EXPECT_NE(text.find("model fitness (no_fingerprint)"), std::string::npos) << text;
  model.provenance.known = true;
  text = names(ModelFitnessWarnings(model, "m.yaml"));
  EXPECT_NE(text.find("model fitness (blank_serial)"), std::string::npos) << text;
  EXPECT_EQ(text.find("no_provenance"), std::string::npos) << text;
  model.provenance.camera_serial = "IRDV0001";
  model.blur_calibration.noise_at_1m_px2 = 0.01;
  EXPECT_TRUE(ModelFitnessWarnings(model, "m.yaml").empty());
}

// The optics fingerprint: named when the first assessed bracket's blur is not the model's.
TEST(ModelFitness, OpticsFingerprintWarnsOnlyWhenTheFirstCheckIsFlagged) {
  CalibrationModel model;
  model.ranges.d_min_mm = 1500.0;
  model.ranges.d_max_mm = 3000.0;
  HealthCheck h;
  h.assessed = true;
  h.blur_var_px2 = 0.9;
  h.calibrated_px2 = 0.57;
  EXPECT_EQ(OpticsFingerprintWarning(model, h, 2000.0), "");
  h.flagged = true;
  const std::string w = OpticsFingerprintWarning(model, h, 2000.0);
  EXPECT_NE(w.find("model fitness (optics_differ)"), std::string::npos) << w;
  EXPECT_NE(w.find("1500 mm"), std::string::npos) << w;
  EXPECT_NE(w.find("2250 mm"), std::string::npos) << w;
  EXPECT_NE(w.find("recalibrate"), std::string::npos) << w;
}

}  // namespace
}  // namespace irdist
