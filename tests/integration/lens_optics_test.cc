// Lenses that are not a round Gaussian, end to end on the virtual rig (docs/virtual-rig.md
// "Optics"): each optic calibrated on its own (reduced) calibration recipe, then validated with
// its own model on face-on and tilted poses. An astigmatic lens (an elliptical PSF, axes 1:1.5,
// turned away from the rows, at two angles) must not be read as tilt: a face-on IRED reads
// theta <= 1 deg in the median (or the round lens's, whose noise alone reads about as much: theta
// is >= 0) and its distances stay within 0.1% (median) and 3x the Cramer-Rao bound (rms); a
// defocused lens (the geometric disc) and a lens with veiling glare (3% of the light in a halo)
// calibrate to a model every reader loads and validate within bounds. Two sensors outside the
// blob fit's pixel family (a 70% pixel aperture; all the blur after the pixels) validate as well.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <string>
#include <utility>
#include <vector>

#include "app/processing/estimates_csv.h"
#include "estimator/model_file.h"
#include "tests/integration/measure_helpers.h"
#include "tests/integration/run_helpers.h"
#include "tests/loopback_gvcp.h"
#include "tests/sanitized_build.h"

namespace irdist {
namespace {

using testing::ReadAll;
using testing::RunIrdist;
using testing::WriteAll;

// Under the sanitizers (tests/sanitized_build.h) the optics whose calibration and validation run
// no code path that another optic here does not are skipped: the astigmatic lenses (the PSF's
// anisotropy is fitted and removed for every lens, the round one's too; estimator/psf_anisotropy
// tests it against known anisotropies), the halo (its edge's excess kurtosis is the defocus
// disc's path with the other sign), the 70% aperture and the Airy lens (the renderer's, whose own
// tests run under the sanitizers too: sim/lens_psf, sim/rig_physics). Each is 40-50 s of the
// camera tests' serial time there, which is the sanitized suite's wall time. The Release suite
// runs and asserts them all.
#define SKIP_UNDER_SANITIZERS()                                                        \
  do {                                                                                 \
    if (testing::kSanitizedBuild) GTEST_SKIP() << "the Release suite runs this optic"; \
  } while (false)

// Face-on and tilted poses inside the calibrated range, between the reduced calibration's 1500,
// 2000 and 2500 mm, two currents, 3 brackets each.
constexpr const char* kValidationRecipe = R"(name: lens-validation
rig: virtual
after: estimate
axes:
  slide_mm: [1700, 2300]
  theta_deg: [0, 20]
  bias_ma: [480, 525]
bracket:
  t_ref_ms: 8
  t_meas_ms: [30, 34]
  repeats: 3
)";

using RigKeys = std::vector<std::pair<std::string, YAML::Node>>;

// The shipped virtual rig with these `virtual.optics:` and `virtual.sensor:` keys.
std::string RigWith(const RigKeys& optics, const RigKeys& sensor = {}) {
  YAML::Node rig = YAML::LoadFile(std::string(IRDIST_SOURCE_DIR) + "/recipes/rigs/virtual.yaml");
  for (const auto& [key, value] : optics) rig["virtual"]["optics"][key] = value;
  for (const auto& [key, value] : sensor) rig["virtual"]["sensor"][key] = value;
  YAML::Emitter out;
  out << rig;
  return std::string(out.c_str()) + "\n";
}

// What one optic's calibration and validation gave.
struct LensRun {
  int calibrate_code = -1, validate_code = -1;
  std::string calibrate_output, validate_output;
  std::string model_path;
  std::vector<EstimateRow> joint;  // the default method's joint rows
  double error_over_bound_rms = NAN;
};

LensRun CalibrateAndValidate(const std::string& name, const std::string& rig_text) {
  LensRun run;
  const std::string dir = testing::ScratchDir("lens_optics_" + name);
  const std::string rig_path = dir + "/rig.yaml";
  WriteAll(rig_path, rig_text);
  std::string calibration = testing::SmallCalibrationRecipe("lens-" + name);
  calibration.replace(calibration.find("rig: virtual"), 12, "rig: " + rig_path);
  WriteAll(dir + "/calibration.yaml", calibration);
  std::string validation = kValidationRecipe;
  validation.replace(validation.find("rig: virtual"), 12, "rig: " + rig_path);
  WriteAll(dir + "/validation.yaml", validation);
  testing::LoopbackGvcpLock lock;
  run.calibrate_code = RunIrdist({"calibrate", dir + "/calibration.yaml", "--out", dir + "/cal",
                                  "--time-scale", "50", "--quiet"},
                                 dir + "/calibrate.log", &run.calibrate_output,
                                 std::chrono::seconds(300));
  run.model_path = dir + "/cal/model.yaml";
  if (run.calibrate_code != 0) return run;
  run.validate_code = RunIrdist({"validate", dir + "/validation.yaml", "--model", run.model_path,
                                 "--out", dir + "/val", "--time-scale", "50"},
                                dir + "/validate.log", &run.validate_output,
                                std::chrono::seconds(300));
  if (run.validate_code != 0) return run;
  for (const EstimateRow& row : ReadEstimatesCsv(dir + "/val/estimates.csv")) {
    if (row.method == "i0_free" && row.dt_ms == 0.0) run.joint.push_back(row);
  }
  const YAML::Node summary = YAML::LoadFile(dir + "/val/summary.yaml");
  run.error_over_bound_rms = summary["crb"]["distance_error_over_bound_rms"].as<double>();
  return run;
}

// The median of `values` (NaN when empty).
double Median(std::vector<double> values) {
  if (values.empty()) return NAN;
  std::sort(values.begin(), values.end());
  return values[values.size() / 2];
}

// The median estimated theta of the face-on rows (a median: theta >= 0, and one bracket's noise
// can read 2 deg where the rest read 0.2), and the median relative distance error (%).
void FaceOnFigures(const LensRun& run, double* median_theta_deg, double* median_rel_pct) {
  std::vector<double> thetas, errors;
  for (const EstimateRow& row : run.joint) {
    errors.push_back(100.0 * std::fabs(row.d_mm / row.true_d_mm - 1.0));
    if (row.true_theta_deg == 0.0) thetas.push_back(row.theta_deg);
  }
  *median_theta_deg = Median(thetas);
  *median_rel_pct = Median(errors);
}

// The joint rows whose health check is not `ok` under the optic's own model ("blur_smaller",
// "blur_larger": a focus change, then measured through with the bracket's own blur).
std::vector<std::string> UnhealthyRows(const LensRun& run) {
  std::vector<std::string> rows;
  for (const EstimateRow& row : run.joint) {
    if (row.health != "ok") {
      rows.push_back(std::to_string(static_cast<int>(row.true_d_mm)) + " mm, " +
                     std::to_string(static_cast<int>(row.true_theta_deg)) + " deg: " + row.health);
    }
  }
  return rows;
}

class LensOptics : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    control_ = new LensRun(CalibrateAndValidate("round", RigWith({})));
  }
  static void TearDownTestSuite() {
    delete control_;
    control_ = nullptr;
  }
  static LensRun* control_;
};
LensRun* LensOptics::control_ = nullptr;

// An astigmatic lens, sd 1.05 px along `angle_deg` and 0.7 px across (axes 1:1.5), calibrated and
// validated with its own model: the PSF's anisotropy is calibrated (model.yaml) and not read as
// tilt.
void ExpectAstigmatismIsNotTilt(const LensRun& control, double angle_deg) {
  ASSERT_EQ(control.calibrate_code, 0) << control.calibrate_output;
  ASSERT_EQ(control.validate_code, 0) << control.validate_output;
  const LensRun run = CalibrateAndValidate("astig" + std::to_string(static_cast<int>(angle_deg)),
                                           RigWith({{"psf_sigma_px", YAML::Node(1.05)},
                                                    {"psf_sigma_minor_px", YAML::Node(0.7)},
                                                    {"psf_angle_deg", YAML::Node(angle_deg)}}));
  ASSERT_EQ(run.calibrate_code, 0) << run.calibrate_output;
  ASSERT_EQ(run.validate_code, 0) << run.validate_output;
  const CalibrationModel model = LoadModel(run.model_path);
  const double turn = 2.0 * angle_deg * 3.14159265358979323846 / 180.0;
  const double half = 0.5 * (1.05 * 1.05 - 0.49);
  EXPECT_NEAR(model.blur_calibration.psf_aniso_c_px2, half * std::cos(turn), 0.03);
  EXPECT_NEAR(model.blur_calibration.psf_aniso_s_px2, half * std::sin(turn), 0.03);
  ASSERT_EQ(run.joint.size(), 24u) << run.validate_output;
  double median_theta = 0.0, median_pct = 0.0, round_theta = 0.0, round_pct = 0.0;
  FaceOnFigures(run, &median_theta, &median_pct);
  FaceOnFigures(control, &round_theta, &round_pct);
  // A face-on IRED's theta is >= 0: its noise alone reads a few tenths of a degree (the round
  // lens); read as tilt, the PSF gave 15-23 deg.
  EXPECT_LE(median_theta, std::max(1.0, 1.3 * round_theta))
      << "angle " << angle_deg << ", the round lens: " << round_theta;
  // The distances: read 1.4-4.2% short before the PSF was calibrated (tens of times the
  // Cramer-Rao bound). Now the median error stays below 0.1% and the rms error over the bound
  // below 3 (the goal, 1.3, is not asserted on this reduced calibration: four runs measured
  // 0.88-0.92 at 30 deg, 0.86-1.72 at -55 deg, the round lens 0.81-0.92; docs/estimator.md).
  EXPECT_LE(median_pct, 0.1) << "angle " << angle_deg << ", the round lens: " << round_pct << "%";
  EXPECT_EQ(UnhealthyRows(run), std::vector<std::string>{}) << "angle " << angle_deg;
  EXPECT_LE(run.error_over_bound_rms, 3.0)
      << "angle " << angle_deg << ", the round lens: " << control.error_over_bound_rms;
  std::cout << "astigmatic lens at " << angle_deg << " deg: face-on median theta " << median_theta
            << " deg (round lens " << round_theta << "), median |d error| " << median_pct
            << "% (round lens " << round_pct << "%), error / CRB rms " << run.error_over_bound_rms
            << " (round lens " << control.error_over_bound_rms << ")\n";
}

TEST_F(LensOptics, AnAstigmaticLensTurnedBy30DegIsNotReadAsTilt) {
  SKIP_UNDER_SANITIZERS();
  ExpectAstigmatismIsNotTilt(*control_, 30.0);
}

// The same lens turned by -55 deg: its PSF's long axis lies nearer the columns, the direction in
// which a pan foreshortens the disc, so what is left of it after calibration reads as a little
// pan tilt (face-on theta 0.24-0.86 deg over four runs, against 0.10-0.16 at 30 deg).
TEST_F(LensOptics, AnAstigmaticLensTurnedByMinus55DegIsNotReadAsTilt) {
  SKIP_UNDER_SANITIZERS();
  ExpectAstigmatismIsNotTilt(*control_, -55.0);
}

// A defocused lens (the thin lens focused at 1 m: a uniform disc of 1.0-2.0 px radius over
// 1.5-3 m, convolved with a 0.5 px Gaussian) and a lens with veiling glare (3% of the light in a
// halo of sd 8 px): each calibrates to a model that loads (the readers' bounds) and validates
// within a few times the round lens's error over the bound.
TEST_F(LensOptics, DefocusDiscAndHaloLensesCalibrateToLoadableModels) {
  ASSERT_EQ(control_->calibrate_code, 0) << control_->calibrate_output;
  const std::vector<std::pair<std::string, std::string>> optics = {
      {"defocus", RigWith({{"psf_sigma_px", YAML::Node(0.5)},
                           {"focus_mm", YAML::Node(1000.0)},
                           {"defocus_disc", YAML::Node(true)}})},
      {"halo", RigWith({{"halo_share", YAML::Node(0.03)}, {"halo_sigma_px", YAML::Node(8.0)}})}};
  double round_theta = 0.0, round_pct = 0.0;
  FaceOnFigures(*control_, &round_theta, &round_pct);
  for (const auto& [name, rig] : optics) {
    if (testing::kSanitizedBuild && name == "halo") continue;  // SKIP_UNDER_SANITIZERS's reason
    const LensRun run = CalibrateAndValidate(name, rig);
    ASSERT_EQ(run.calibrate_code, 0) << name << "\n" << run.calibrate_output;
    EXPECT_NO_THROW(LoadModel(run.model_path)) << name;
    ASSERT_EQ(run.validate_code, 0) << name << "\n" << run.validate_output;
    ASSERT_EQ(run.joint.size(), 24u) << name;
    double median_theta = 0.0, median_pct = 0.0;
    FaceOnFigures(run, &median_theta, &median_pct);
    std::cout << name << " lens: face-on median theta " << median_theta << " deg (round lens "
              << round_theta << "), median |d error| " << median_pct << "% (round lens "
              << round_pct << "%), error / CRB rms " << run.error_over_bound_rms
              << " (round lens " << control_->error_over_bound_rms << ")\n";
    EXPECT_LE(median_theta, std::max(1.0, 1.3 * round_theta)) << name;
    EXPECT_LE(median_pct, 0.1) << name;  // the goal for the defocus disc's Fig. 10 median
    // Under its own calibration the lens is the calibrated one: no bracket's blur departs from
    // it (the halo's blob-fit blur once read -6% at 2300 mm, and the brackets measured with
    // their own blur read -0.4%).
    EXPECT_EQ(UnhealthyRows(run), std::vector<std::string>{}) << name;
  }
}

// Validates `run`'s model like the round lens's (face-on theta, the median distance error, the
// health, the error over the bound within 3; its goal, 1.3, printed, not asserted at this count).
void ExpectValidatesAsTheRoundLens(const LensRun& control, const LensRun& run,
                                   const std::string& name) {
  ASSERT_EQ(run.validate_code, 0) << name << "\n" << run.validate_output;
  ASSERT_EQ(run.joint.size(), 24u) << name;
  double median_theta = 0.0, median_pct = 0.0, round_theta = 0.0, round_pct = 0.0;
  FaceOnFigures(run, &median_theta, &median_pct);
  FaceOnFigures(control, &round_theta, &round_pct);
  std::cout << name << " sensor: face-on median theta " << median_theta << " deg (round lens "
            << round_theta << "), median |d error| " << median_pct << "% (round lens "
            << round_pct << "%), error / CRB rms " << run.error_over_bound_rms << " (round lens "
            << control.error_over_bound_rms << ")\n";
  EXPECT_LE(median_theta, std::max(1.0, 1.3 * round_theta)) << name;
  EXPECT_LE(median_pct, 0.1) << name;
  EXPECT_EQ(UnhealthyRows(run), std::vector<std::string>{}) << name;
  EXPECT_LE(run.error_over_bound_rms, 3.0) << name;
}

// A sensor whose pixels sense only the central 70% of their pitch (a fill factor), behind a
// 0.5 px lens: outside the blob fit's pixel family (the whole pixel's box), it calibrates to a
// model that loads and validates as the round lens does.
TEST_F(LensOptics, APixelApertureOf70PercentCalibratesAndValidates) {
  SKIP_UNDER_SANITIZERS();
  ASSERT_EQ(control_->calibrate_code, 0) << control_->calibrate_output;
  const LensRun run = CalibrateAndValidate(
      "fill70",
      RigWith({{"psf_sigma_px", YAML::Node(0.5)}}, {{"pixel_aperture", YAML::Node(0.7)}}));
  ASSERT_EQ(run.calibrate_code, 0) << run.calibrate_output;
  EXPECT_NO_THROW(LoadModel(run.model_path));
  ExpectValidatesAsTheRoundLens(*control_, run, "fill70");
}

// A diffraction-limited lens (issue 31's Airy-like PSF): the Airy pattern with its first dark ring
// at 1 px, convolved with a 0.5 px core and the rig's defocus; its rings are outside the blob fit's
// Gaussian family. It calibrates to a model that loads and validates as the round lens does.
TEST_F(LensOptics, AnAiryLensCalibratesAndValidates) {
  SKIP_UNDER_SANITIZERS();
  ASSERT_EQ(control_->calibrate_code, 0) << control_->calibrate_output;
  const LensRun run = CalibrateAndValidate(
      "airy",
      RigWith({{"psf_sigma_px", YAML::Node(0.5)}, {"airy_first_zero_px", YAML::Node(1.0)}}));
  ASSERT_EQ(run.calibrate_code, 0) << run.calibrate_output;
  EXPECT_NO_THROW(LoadModel(run.model_path));
  ExpectValidatesAsTheRoundLens(*control_, run, "airy");
}

// All the blur after the pixels (issue 31's renderer): a sharp lens, no defocus, the charge
// spread by a Gaussian of 1 px sampled on the pixels and cut at 4 sd. The calibration's blur split
// finds it after the pixels, and the model validates as the round lens's.
TEST_F(LensOptics, AllTheBlurAfterThePixelsCalibratesAndValidates) {
  ASSERT_EQ(control_->calibrate_code, 0) << control_->calibrate_output;
  const LensRun run = CalibrateAndValidate(
      "all_after", RigWith({{"psf_sigma_px", YAML::Node(0.0)}, {"focus_mm", YAML::Node(0.0)}},
                           {{"crosstalk_sigma_px", YAML::Node(1.0)},
                            {"crosstalk_shape", YAML::Node("sampled_gaussian")}}));
  ASSERT_EQ(run.calibrate_code, 0) << run.calibrate_output;
  const CalibrationModel model = LoadModel(run.model_path);
  EXPECT_TRUE(model.fitness.passed);
  ExpectValidatesAsTheRoundLens(*control_, run, "all_after");
}

}  // namespace
}  // namespace irdist
