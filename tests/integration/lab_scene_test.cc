// A lab's scene on the virtual rig, end to end: a clean calibration, then one
// validation per fault the rig file adds (docs/virtual-rig.md, "A lab's scene"): defect pixels,
// ambient light, a reflection off the table 25 px and 8 px away, a cable over 15% of the disc, a
// second LED. Each is measured through within the clean run's accuracy, or named by its own flag on
// (nearly) every bracket; none is silently wrong, and a reflection or a cable is never called
// motion or a focus change.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "app/processing/estimates_csv.h"
#include "tests/integration/measure_helpers.h"
#include "tests/integration/run_helpers.h"
#include "tests/loopback_gvcp.h"

namespace irdist {
namespace {

using testing::RunIrdist;
using testing::WriteAll;

// 5 distances x 4 angles x 2 currents: a calibration whose I0-free Sigma model is well posed
// (the 3-distance one of the other tests leaves it ill-conditioned, a pole inside the range).
const char* const kCalibrationSlidesMm = "[1500, 1750, 2000, 2250, 2500]";

// 3 distances x 2 angles at one current: 6 brackets per fault.
std::string ValidationRecipe(const std::string& rig_path) {
  return "name: lab-scene\nrig: " + rig_path + R"(
after: estimate
axes:
  slide_mm: [1700, 2100, 2450]
  theta_deg: [0, 25]
  bias_ma: [490]
bracket:
  t_ref_ms: 8
  t_meas_ms: [30, 36]
)";
}

// The shipped virtual rig with `fault` merged into its `virtual:` section.
std::string RigWith(const std::string& fault_yaml) {
  YAML::Node rig = YAML::LoadFile(std::string(IRDIST_SOURCE_DIR) + "/recipes/rigs/virtual.yaml");
  const YAML::Node fault = YAML::Load(fault_yaml);
  for (const auto& section : fault) {
    for (const auto& key : section.second) {
      rig["virtual"][section.first.as<std::string>()][key.first.as<std::string>()] = key.second;
    }
  }
  YAML::Emitter out;
  out << rig;
  return std::string(out.c_str()) + "\n";
}

struct Case {
  std::string name;
  std::string fault;  // YAML merged into `virtual:`
};

const std::vector<Case>& Cases() {
  static const std::vector<Case> cases = {
      {"control", ""},
      {"defects",
       "sensor: {hot_pixels: 20, hot_rate_e_per_s: [180000, 300000], stuck_pixels: 10, "
       "stuck_level_dn: [1000, 4095], defect_seed: 3, defects_near_blob: 3}"},
      {"ambient", "scene: {ambient: {center_e_per_s: 6000, gradient_x_percent: 100}}"},
      {"reflection25", "scene: {reflection: {plane_below_mm: 8.3, reflectance: 0.2}}"},
      {"reflection8", "scene: {reflection: {plane_below_mm: 2.65, reflectance: 0.2}}"},
      {"cable15", "scene: {occluder: {covered_fraction: 0.15, edge_angle_deg: 90}}"},
      {"second_led",
       "scene: {second_source: {position_mm: [20, 0, 2000], diameter_mm: 5, "
       "intensity_mw_sr: 27}}"},
  };
  return cases;
}

// The default method's joint rows of a validation.
using Rows = std::vector<EstimateRow>;

class LabScene : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new std::string(testing::ScratchDir("lab_scene"));
    rows_ = new std::map<std::string, Rows>;
    logs_ = new std::map<std::string, std::string>;
    testing::LoopbackGvcpLock lock;
    WriteAll(*dir_ + "/calibration.yaml",
             testing::SmallCalibrationRecipe("lab-calibration", kCalibrationSlidesMm));
    std::string log;
    calibrated_ = RunIrdist({"calibrate", *dir_ + "/calibration.yaml", "--out", *dir_ + "/cal",
                             "--time-scale", "50", "--quiet"},
                            *dir_ + "/calibrate.log", &log) == 0;
    if (!calibrated_) return;
    for (const Case& c : Cases()) Validate(c);
  }
  static void Validate(const Case& c) {
    const std::string rig = *dir_ + "/" + c.name + "-rig.yaml";
    WriteAll(rig, RigWith(c.fault));
    WriteAll(*dir_ + "/" + c.name + ".yaml", ValidationRecipe(rig));
    std::string& log = (*logs_)[c.name];
    const int code =
        RunIrdist({"validate", *dir_ + "/" + c.name + ".yaml", "--model", *dir_ + "/cal/model.yaml",
                   "--out", *dir_ + "/" + c.name, "--time-scale", "50", "--quiet"},
                  *dir_ + "/" + c.name + ".log", &log);
    if (code != 0) return;
    for (const EstimateRow& r : ReadEstimatesCsv(*dir_ + "/" + c.name + "/estimates.csv")) {
      if (r.method == "i0_free" && r.dt_ms == 0.0) (*rows_)[c.name].push_back(r);
    }
  }
  static void TearDownTestSuite() {
    delete dir_;
    delete rows_;
    delete logs_;
  }
  // The rows of `name`, asserted to be a whole validation.
  static const Rows& RowsOf(const std::string& name) {
    static const Rows none;
    EXPECT_TRUE(calibrated_) << "the calibration failed: " << *dir_ << "/calibrate.log";
    const auto it = rows_->find(name);
    EXPECT_TRUE(it != rows_->end() && it->second.size() == 6u) << name << ": " << (*logs_)[name];
    return it == rows_->end() ? none : it->second;
  }
  static std::string* dir_;
  static std::map<std::string, Rows>* rows_;
  static std::map<std::string, std::string>* logs_;
  static bool calibrated_;
};

std::string* LabScene::dir_ = nullptr;
std::map<std::string, Rows>* LabScene::rows_ = nullptr;
std::map<std::string, std::string>* LabScene::logs_ = nullptr;
bool LabScene::calibrated_ = false;

double ErrorPct(const EstimateRow& r) {
  return 100.0 * std::abs(r.d_mm - r.true_d_mm) / r.true_d_mm;
}

bool Has(const EstimateRow& r, const char* flag) {
  return std::any_of(r.flags.begin(), r.flags.end(),
                     [flag](const EstimateFlag& f) { return f.name == flag; });
}

// The control's row at r's pose (nullptr when there is none).
const EstimateRow* AtPose(const Rows& control, const EstimateRow& r) {
  for (const EstimateRow& c : control) {
    if (c.true_d_mm == r.true_d_mm && c.true_theta_deg == r.true_theta_deg) return &c;
  }
  return nullptr;
}

// Measured through, judged against the control at the same pose: both share one calibration, so
// its own error at a pose (up to 1.5 se at 2100 mm, 25 deg) cancels in the difference. Each row's
// error departs from the control's by at most 5 of their combined standard errors plus
// `allowance_pct` of the distance (a fault may leave a small systematic part); over the rows, the
// departures' rms in those units is at most 2.5 (no bias beyond the noise); the row's standard
// error is at most `noise_factor` times the control's. The noise of each frame is the yardstick,
// not another run's draw: two runs' maxima over six noisy rows differ by their noise alone.
void ExpectAsTheControl(const Rows& rows, const Rows& control, const std::string& name,
                        double allowance_pct, double noise_factor) {
  double sum_z2 = 0.0;
  int count = 0;
  for (const EstimateRow& r : rows) {
    const EstimateRow* c = AtPose(control, r);
    ASSERT_TRUE(c != nullptr && c->ok && r.ok && c->d_std_mm > 0.0 && r.d_std_mm > 0.0)
        << name << " " << r.true_d_mm << " mm: no estimate or no standard error";
    const double se_mm = std::hypot(r.d_std_mm, c->d_std_mm);
    const double departure_mm = r.d_mm - c->d_mm;
    EXPECT_LE(std::abs(departure_mm), 5.0 * se_mm + allowance_pct / 100.0 * r.true_d_mm)
        << name << " " << r.true_d_mm << " mm " << r.true_theta_deg << " deg: error " << ErrorPct(r)
        << "% (control " << ErrorPct(*c) << "%), se " << se_mm << " mm, " << FlagsCell(r.flags);
    EXPECT_LE(r.d_std_mm, noise_factor * c->d_std_mm) << name << " " << r.true_d_mm << " mm";
    sum_z2 += (departure_mm / se_mm) * (departure_mm / se_mm);
    ++count;
  }
  if (count > 0) {
    EXPECT_LE(std::sqrt(sum_z2 / count), 2.5) << name << ": biased against the control";
  }
}

// Trusted, but for the motion check's rare false alarm (about 1 in 1000 brackets; the caller
// allows one over its runs).
bool TrustedButForMoving(const EstimateRow& r) {
  if (!r.ok) return false;
  for (const EstimateFlag& f : r.flags) {
    const FlagSpec* spec = FindFlagSpec(f.name);
    if (f.name != "moving" && (spec == nullptr || spec->suspect)) return false;
  }
  return true;
}

// No trusted row off by more than max(0.3%, 4 standard errors); no reflection, cable or second
// source read as motion or focus.
void ExpectNoneSilentlyWrong(const Rows& rows, const std::string& name) {
  for (const EstimateRow& r : rows) {
    const std::string what = name + " " + std::to_string(static_cast<int>(r.true_d_mm)) + " mm " +
                             std::to_string(static_cast<int>(r.true_theta_deg)) +
                             " deg: " + FlagsCell(r.flags) + ", error " +
                             std::to_string(ErrorPct(r)) + "%";
    if (r.Trusted()) {
      EXPECT_LE(std::abs(r.d_mm - r.true_d_mm),
                std::max(0.003 * r.true_d_mm, 4.0 * std::max(r.d_std_mm, 0.0)))
          << what;
    }
    if (name != "control" && name != "defects" && name != "ambient") {
      EXPECT_FALSE(Has(r, "moving") || Has(r, "blur_larger") || Has(r, "blur_smaller")) << what;
    }
  }
}

TEST_F(LabScene, AControlRunIsCleanAndNothingIsSilentlyWrong) {
  int moving = 0;
  for (const EstimateRow& r : RowsOf("control")) {
    EXPECT_TRUE(TrustedButForMoving(r)) << FlagsCell(r.flags);
    moving += Has(r, "moving") ? 1 : 0;
  }
  EXPECT_LE(moving, 1) << "a static IRED read as moving";
  for (const Case& c : Cases()) ExpectNoneSilentlyWrong(RowsOf(c.name), c.name);
}

// Defect pixels and ambient light are measured through: every bracket estimated and trusted (but
// for one false `moving` over both runs), its error as the control's within their noise, its noise
// at most 2x the control's, the health still assessed on every bracket.
TEST_F(LabScene, DefectPixelsAndAmbientLightAreMeasuredThrough) {
  int moving = 0;
  for (const char* name : {"defects", "ambient"}) {
    const Rows& rows = RowsOf(name);
    ExpectAsTheControl(rows, RowsOf("control"), name, 0.02, 2.0);
    for (const EstimateRow& r : rows) {
      EXPECT_TRUE(TrustedButForMoving(r)) << name << ": " << FlagsCell(r.flags);
      moving += Has(r, "moving") ? 1 : 0;
      EXPECT_NE(r.health, "-") << name << ": health not assessed";
    }
  }
  EXPECT_LE(moving, 1) << "a static IRED read as moving";
  int noted = 0;
  for (const EstimateRow& r : RowsOf("defects")) noted += Has(r, "defect_pixels") ? 1 : 0;
  EXPECT_GE(noted, 5) << "the defects near the blob are noted";
}

// A reflection 17-33 px away and a second LED 30 px away are masked and measured through (as the
// control within their noise plus 0.05%), or named second_source where their light reaches the
// IRED's.
TEST_F(LabScene, SeparateSourcesAreMaskedOrNamed) {
  for (const char* name : {"reflection25", "second_led"}) {
    Rows masked;
    for (const EstimateRow& r : RowsOf(name)) {
      if (Has(r, "second_source")) continue;
      EXPECT_TRUE(Has(r, "other_blobs")) << name << ": " << FlagsCell(r.flags);
      masked.push_back(r);
    }
    ExpectAsTheControl(masked, RowsOf("control"), name, 0.05, 2.0);
  }
}

// A reflection touching the blob is named on every bracket; a cable over 15% of the disc too.
TEST_F(LabScene, AMergedReflectionAndACableAreNamed) {
  for (const auto& [name, flag] : std::vector<std::pair<std::string, const char*>>{
           {"reflection8", "second_source"}, {"cable15", "occluded"}}) {
    for (const EstimateRow& r : RowsOf(name)) {
      EXPECT_TRUE(Has(r, flag)) << name << ": " << FlagsCell(r.flags);
      EXPECT_FALSE(r.Trusted()) << name;
    }
  }
}

}  // namespace
}  // namespace irdist

namespace irdist {
namespace {

// `irdist check` looks at the images too: each bracket's scene, as a report (exit 0).
TEST_F(LabScene, CheckReportsEachBracketsScene) {
  const std::map<std::string, std::string> expected = {
      {"control", "6 brackets; 0 with a second source"},
      {"reflection8", "6 brackets; 6 with a second source"},
      {"cable15", "6 brackets; 6 with a second source, an occluded disc"},
      {"defects", "6 with defect pixels"},
      {"second_led", "6 with other blobs"}};
  for (const auto& [name, text] : expected) {
    std::string output;
    EXPECT_EQ(RunIrdist({"check", *dir_ + "/" + name + "/recording"},
                        *dir_ + "/check-" + name + ".log", &output),
              0)
        << output;
    EXPECT_NE(output.find(text), std::string::npos) << name << ":\n" << output;
  }
  std::string output;
  RunIrdist({"check", *dir_ + "/cable15/recording"}, *dir_ + "/check-cable.log", &output);
  EXPECT_NE(output.find("occluded"), std::string::npos) << output;
}

}  // namespace
}  // namespace irdist
