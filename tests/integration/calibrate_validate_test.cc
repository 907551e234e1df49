// End to end on the virtual rig, through the built binary: a short calibration (recording complete
// and checked, model.yaml loads, report), a short validation with that model (estimates.csv,
// summary.yaml with its documented keys, report), playback reproducing the live features.csv and
// estimates.csv byte for byte, `irdist fit` on the recording, and `irdist check` flagging a
// corrupted copy of the recording.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <memory>
#include <set>

#include "acquisition/recording_check.h"
#include "acquisition/recording_reader.h"
#include "app/processing/validation_summary.h"
#include "estimator/model_file.h"
#include "tests/integration/measure_helpers.h"
#include "tests/integration/run_helpers.h"
#include "tests/loopback_gvcp.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;
using testing::ReadAll;
using testing::RunIrdist;
using testing::WriteAll;

// 3 distances x 4 angles x 2 currents = 24 poses x 4 frames: 72 differences, enough for the
// reduced I0-free models (the shipped smoke recipe is too small to fit them).
const std::string kCalibrationRecipe = testing::SmallCalibrationRecipe("it-calibration");

// Inside the calibrated range; a current not seen in calibration (525 mA).
constexpr const char* kValidationRecipe = R"(name: it-validation
rig: virtual
after: estimate
axes:
  slide_mm: [1700, 2300]
  theta_deg: [10, 25]
  bias_ma: [480, 525]
bracket:
  t_ref_ms: 8
  t_meas_ms: [30, 34]
)";

constexpr const char* kTimeScale = "50";

class CalibrateValidate : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new std::string(testing::ScratchDir("calibrate_validate"));
    WriteAll(*dir_ + "/calibration.yaml", kCalibrationRecipe);
    WriteAll(*dir_ + "/validation.yaml", kValidationRecipe);
    testing::LoopbackGvcpLock lock;
    calibrate_code_ = RunIrdist({"calibrate", *dir_ + "/calibration.yaml", "--out", *dir_ + "/cal",
                                 "--time-scale", kTimeScale},
                                *dir_ + "/calibrate.log", calibrate_output_);
    validate_code_ =
        RunIrdist({"validate", *dir_ + "/validation.yaml", "--model", *dir_ + "/cal/model.yaml",
                   "--out", *dir_ + "/val", "--time-scale", kTimeScale},
                  *dir_ + "/validate.log", validate_output_);
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }

  static std::string* dir_;
  static int calibrate_code_;
  static int validate_code_;
  static std::string calibrate_output_[1];
  static std::string validate_output_[1];
};

std::string* CalibrateValidate::dir_ = nullptr;
int CalibrateValidate::calibrate_code_ = -1;
int CalibrateValidate::validate_code_ = -1;
std::string CalibrateValidate::calibrate_output_[1];
std::string CalibrateValidate::validate_output_[1];

TEST_F(CalibrateValidate, CalibrationRecordsEveryBracketFitsAndReports) {
  ASSERT_EQ(calibrate_code_, 0) << calibrate_output_[0];
  const std::string run = *dir_ + "/cal";
  const RecordingCheck check = CheckRecording(run + "/recording");
  EXPECT_TRUE(check.ok()) << check.BriefReport();
  EXPECT_EQ(check.completion, Completion::kComplete);
  EXPECT_EQ(check.rows, 24 * 4);
  EXPECT_EQ(check.complete_brackets, 24);

  const RecordingReader reader(run + "/recording");
  EXPECT_NE(reader.header().recipe_text.find("it-calibration"), std::string::npos);
  EXPECT_NE(reader.header().rig_text.find("kind: virtual"), std::string::npos);
  EXPECT_EQ(reader.header().camera.serial, "IRDV0001");
  EXPECT_FALSE(reader.header().camera_features.empty());
  // The shipped virtual rig's region of interest reaches the camera (roi_px in the rig file).
  const auto& features = reader.header().camera_features;
  ASSERT_TRUE(features.count("Width") && features.count("OffsetX")) << reader.header().rig_text;
  EXPECT_EQ(features.at("Width"), "256");
  EXPECT_EQ(features.at("Height"), "256");
  EXPECT_EQ(features.at("OffsetX"), "512");
  EXPECT_EQ(features.at("OffsetY"), "384");
  EXPECT_FALSE(reader.header().station_identity.empty());
  // Ground truth and the measured current travel with each frame.
  std::set<double> slides;
  for (const FrameRecord& row : reader.rows()) {
    slides.insert(row.slide_mm);
    EXPECT_NEAR(row.bias_ma_measured, row.bias_ma_set, 1.0) << "line " << row.line;
  }
  EXPECT_EQ(slides, (std::set<double>{1500.0, 2000.0, 2500.0}));

  const CalibrationModel model = LoadModel(run + "/model.yaml");
  EXPECT_NE(model.Find(ModelKind::kFreeE), nullptr);
  EXPECT_NE(model.Find(ModelKind::kFreeSigma), nullptr);
  EXPECT_DOUBLE_EQ(model.ranges.d_min_mm, 1500.0);
  EXPECT_DOUBLE_EQ(model.ranges.d_max_mm, 2500.0);
  EXPECT_NE(calibrate_output_[0].find("free_sigma"), std::string::npos) << calibrate_output_[0];
  // Three distances only: the fit says the Sigma model will interpolate poorly between them.
  EXPECT_NE(calibrate_output_[0].find("3 calibrated distances"), std::string::npos)
      << calibrate_output_[0];

  EXPECT_TRUE(fs::exists(run + "/report/index.html"));
  EXPECT_NE(ReadAll(run + "/report/index.html").find("Fig. 7"), std::string::npos);
  EXPECT_GT(testing::CountLines(run + "/station.log"), 100);
  EXPECT_EQ(testing::CountLines(run + "/features.csv"), 1 + 24 * 4);
}

// A good calibration on the virtual rig passes its own fitness, and the figure is
// in model.yaml, the output and the report.
TEST_F(CalibrateValidate, AGoodCalibrationPassesItsFitness) {
  ASSERT_EQ(calibrate_code_, 0) << calibrate_output_[0];
  const CalibrationModel model = LoadModel(*dir_ + "/cal/model.yaml");
  const CalibrationFitness& f = model.fitness;
  ASSERT_TRUE(f.assessed) << calibrate_output_[0];
  EXPECT_TRUE(f.passed) << f.BriefReport();
  EXPECT_EQ(f.poses, 24);
  EXPECT_GT(f.dof, 24);
  EXPECT_LE(f.reduced_chi2, f.limit);
  EXPECT_FALSE(f.worst.empty());
  EXPECT_NE(calibrate_output_[0].find("fitness: reduced chi-square"), std::string::npos)
      << calibrate_output_[0];
  EXPECT_NE(ReadAll(*dir_ + "/cal/report/index.html").find("fitness"), std::string::npos);
  EXPECT_FALSE(fs::exists(*dir_ + "/cal/model.rejected.yaml"));
}

TEST_F(CalibrateValidate, ValidationWritesEstimatesSummaryAndReport) {
  ASSERT_EQ(calibrate_code_, 0) << calibrate_output_[0];
  ASSERT_EQ(validate_code_, 0) << validate_output_[0];
  const std::string run = *dir_ + "/val";
  EXPECT_TRUE(CheckRecording(run + "/recording").ok());
  const std::vector<EstimateRow> rows = ReadEstimatesCsv(run + "/estimates.csv");
  std::set<std::string> methods;
  int joint_i0_free = 0;
  for (const EstimateRow& row : rows) {
    methods.insert(row.method);
    if (row.method == "i0_free" && row.dt_ms == 0.0) {
      ++joint_i0_free;
      EXPECT_TRUE(row.ok) << "bracket " << row.bracket;
      // A sane estimate of a pose inside the calibrated range (the accuracy goals are measured
      // by the full recipes, not asserted here).
      EXPECT_NEAR(row.d_mm, row.true_d_mm, 0.1 * row.true_d_mm) << "bracket " << row.bracket;
    }
  }
  EXPECT_EQ(joint_i0_free, 8);
  EXPECT_TRUE(methods.count("i0_free") && methods.count("geometric"));

  const YAML::Node summary = YAML::LoadFile(run + "/summary.yaml");
  for (const char* key :
       {"count", "distance_rel_error_pct", "distance_abs_error_mm", "theta_abs_error_deg",
        "current_shift_pct", "dispersion_mm", "by_dt", "best_dt_ms", "outside_calibrated_range"}) {
    EXPECT_TRUE(summary[key].IsDefined()) << key;
  }
  EXPECT_EQ(summary["count"].as<int>(), 8);
  for (const char* key : {"median", "p95", "max"}) {
    EXPECT_TRUE(summary["distance_rel_error_pct"][key].IsDefined()) << key;
  }
  EXPECT_TRUE(summary["by_dt"]["22"].IsDefined() || summary["by_dt"]["22.0"].IsDefined())
      << ReadAll(run + "/summary.yaml");
  EXPECT_TRUE(summary["geometric"].IsDefined());
  EXPECT_TRUE(fs::exists(run + "/report/index.html"));
  EXPECT_NE(validate_output_[0].find("i0_free"), std::string::npos);
}

// The virtual rig's Cramer-Rao bound sits beside each method's figures (app/processing/crb.h): the
// bound of every pose of the recipe, the errors in units of it, and the report's header says the
// same.
TEST_F(CalibrateValidate, ValidationSummaryCarriesTheCramerRaoBound) {
  ASSERT_EQ(validate_code_, 0) << validate_output_[0];
  const std::string run = *dir_ + "/val";
  const YAML::Node summary = YAML::LoadFile(run + "/summary.yaml");
  for (const YAML::Node& block : {summary, summary["geometric"]}) {
    const YAML::Node crb = block["crb"];
    ASSERT_TRUE(crb.IsMap()) << ReadAll(run + "/summary.yaml");
    EXPECT_NE(crb["source"].as<std::string>().find("virtual rig physics"), std::string::npos);
    EXPECT_EQ(crb["conditions"].as<int>(), 8);  // 2 distances x 2 angles x 2 currents
    const double lo = crb["distance_sd_bound_mm"]["min"].as<double>();
    const double hi = crb["distance_sd_bound_mm"]["max"].as<double>();
    // A few mm per estimate at 1.7-2.3 m with two frames (the Fig. 14 pose at 2.7 m: 1.8 mm).
    EXPECT_GT(lo, 0.1);
    EXPECT_LT(hi, 10.0);
    EXPECT_GT(crb["distance_error_over_bound_rms"].as<double>(), 0.0);
    EXPECT_EQ(crb["theta_ge_15"]["count"].as<int>(), 4);  // the 25 deg poses
    EXPECT_GT(crb["theta_ge_15"]["theta_sd_bound_deg_min"].as<double>(), 0.0);
    EXPECT_TRUE(crb["dispersion"].IsSequence());
    EXPECT_EQ(crb["dispersion"].size(), 0u);  // no repetitions in this recipe
  }
  EXPECT_NE(ReadAll(run + "/report/index.html").find("CRB i0_free"), std::string::npos);
}

TEST_F(CalibrateValidate, PlaybackReproducesTheLiveFilesByteForByte) {
  ASSERT_EQ(validate_code_, 0) << validate_output_[0];
  const std::string run = *dir_ + "/val";
  std::string output;
  ASSERT_EQ(RunIrdist({"playback", run + "/recording", "--model", *dir_ + "/cal/model.yaml",
                       "--out", *dir_ + "/playback"},
                      *dir_ + "/playback.log", &output),
            0)
      << output;
  const std::string live_features = ReadAll(run + "/features.csv");
  ASSERT_FALSE(live_features.empty());
  EXPECT_TRUE(live_features == ReadAll(*dir_ + "/playback/features.csv"));
  const std::string live_estimates = ReadAll(run + "/estimates.csv");
  ASSERT_FALSE(live_estimates.empty());
  EXPECT_TRUE(live_estimates == ReadAll(*dir_ + "/playback/estimates.csv"));
  EXPECT_TRUE(ReadAll(run + "/summary.yaml").find("count") != std::string::npos);
}

TEST_F(CalibrateValidate, FitFromTheRecordingGivesTheLiveModel) {
  ASSERT_EQ(calibrate_code_, 0) << calibrate_output_[0];
  std::string output;
  ASSERT_EQ(RunIrdist({"fit", *dir_ + "/cal/recording", "--out", *dir_ + "/refit/model.yaml"},
                      *dir_ + "/fit.log", &output),
            0)
      << output;
  EXPECT_TRUE(ReadAll(*dir_ + "/cal/model.yaml") == ReadAll(*dir_ + "/refit/model.yaml"));
  EXPECT_TRUE(ReadAll(*dir_ + "/cal/features.csv") == ReadAll(*dir_ + "/refit/features.csv"));
}

TEST_F(CalibrateValidate, CheckFlagsACorruptedRecording) {
  ASSERT_EQ(validate_code_, 0) << validate_output_[0];
  const std::string copy = *dir_ + "/corrupted";
  fs::copy(*dir_ + "/val/recording", copy, fs::copy_options::recursive);
  std::string output;
  EXPECT_EQ(RunIrdist({"check", copy}, *dir_ + "/check-ok.log", &output), 0) << output;
  // Damage one PNG and one CSV row.
  WriteAll(copy + "/frames/000003.png", "not a png");
  std::string csv = ReadAll(copy + "/frames.csv");
  const size_t line3 = csv.find('\n', csv.find('\n', csv.find('\n') + 1) + 1);
  csv.insert(line3 + 1, "garbage,row\n");
  WriteAll(copy + "/frames.csv", csv);
  EXPECT_EQ(RunIrdist({"check", copy}, *dir_ + "/check-bad.log", &output), 1) << output;
  EXPECT_NE(output.find("000003.png"), std::string::npos) << output;
  EXPECT_NE(output.find("frames.csv:4"), std::string::npos) << output;
}

}  // namespace
}  // namespace irdist
