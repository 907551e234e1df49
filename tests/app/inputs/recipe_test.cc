#include "app/inputs/recipe.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace irdist {
namespace {

const std::string kRecipes = std::string(IRDIST_SOURCE_DIR) + "/recipes";

Recipe Shipped(const std::string& name) { return LoadRecipe(kRecipes + "/" + name); }

void ExpectWithinLimits(const Recipe& recipe, const Plan& plan) {
  const StationLimits& limits = recipe.rig.station.limits;
  for (const Pose& p : plan.poses) {
    EXPECT_TRUE(limits.slide_mm.Contains(p.slide_mm)) << p.slide_mm;
    EXPECT_TRUE(limits.pan_deg.Contains(p.pan_deg)) << p.pan_deg;
    EXPECT_TRUE(limits.tilt_deg.Contains(p.tilt_deg)) << p.tilt_deg;
    EXPECT_TRUE(limits.bias_ma.Contains(p.bias_ma)) << p.bias_ma;
  }
}

std::set<double> Distinct(const Plan& plan, double Pose::*field) {
  std::set<double> values;
  for (const Pose& p : plan.poses) values.insert(p.*field);
  return values;
}

TEST(RecipeTest, Table3ExpandsToThePapersCounts) {
  const Recipe recipe = Shipped("table3-calibration.yaml");
  EXPECT_EQ(recipe.after, AfterRecording::kFit);
  EXPECT_EQ(recipe.rig.kind, RigKind::kVirtual);
  EXPECT_EQ(recipe.rig.name, "virtual");
  const Plan plan = PlanRecipe(recipe);
  EXPECT_EQ(plan.summary.pose_count, 64);
  EXPECT_EQ(plan.summary.frames_per_pose, 5);
  EXPECT_EQ(plan.summary.frame_count, 320);
  EXPECT_EQ(plan.summary.difference_count, 256);
  EXPECT_EQ(Distinct(plan, &Pose::slide_mm), (std::set<double>{1500, 2000, 2500, 3000}));
  EXPECT_EQ(Distinct(plan, &Pose::theta_deg), (std::set<double>{0, 5, 10, 15, 20, 25, 30, 35}));
  EXPECT_EQ(Distinct(plan, &Pose::bias_ma), (std::set<double>{475, 500}));
  EXPECT_EQ(Distinct(plan, &Pose::tilt_deg), (std::set<double>{0}));
  for (const Pose& p : plan.poses) EXPECT_EQ(p.pan_deg, p.theta_deg);  // theta by pan, tilt 0
  std::vector<double> exposures;
  for (const PlannedExposure& f : plan.bracket) exposures.push_back(f.exposure_ms);
  EXPECT_EQ(exposures, (std::vector<double>{8, 30, 32, 34, 36}));
  ExpectWithinLimits(recipe, plan);
  // Every (slide, theta, bias) combination exactly once.
  std::set<std::vector<double>> grid;
  for (const Pose& p : plan.poses) grid.insert({p.slide_mm, p.theta_deg, p.bias_ma});
  EXPECT_EQ(grid.size(), 64u);
}

TEST(RecipeTest, ValidationFig10ExpandsToItsGrid) {
  const Recipe recipe = Shipped("validation-fig10.yaml");
  EXPECT_EQ(recipe.after, AfterRecording::kEstimate);
  const Plan plan = PlanRecipe(recipe);
  EXPECT_EQ(Distinct(plan, &Pose::slide_mm),
            (std::set<double>{1500, 1700, 1900, 2100, 2300, 2500, 2700, 2900}));
  EXPECT_EQ(Distinct(plan, &Pose::theta_deg), (std::set<double>{0, 10, 20, 30}));
  EXPECT_EQ(Distinct(plan, &Pose::bias_ma), (std::set<double>{475, 500, 525}));
  EXPECT_EQ(recipe.sweep.bracket.t_ref_ms, 8.0);
  EXPECT_EQ(recipe.sweep.bracket.t_meas_ms, (std::vector<double>{30, 32, 34, 36, 38, 40}));
  EXPECT_EQ(plan.summary.pose_count, 8 * 4 * 3);
  EXPECT_EQ(plan.summary.frame_count, 96 * 7);
  EXPECT_EQ(plan.summary.difference_count, 96 * 6);
  ExpectWithinLimits(recipe, plan);
}

TEST(RecipeTest, RandomCurrentDrawsTenCurrentsPerPose) {
  const Recipe recipe = Shipped("validation-random-current.yaml");
  const Plan plan = PlanRecipe(recipe);
  EXPECT_EQ(plan.summary.pose_count, 90);
  EXPECT_EQ(plan.summary.frame_count, 180);
  EXPECT_EQ(plan.summary.difference_count, 90);
  EXPECT_EQ(Distinct(plan, &Pose::slide_mm), (std::set<double>{1700, 2300, 2900}));
  EXPECT_EQ(Distinct(plan, &Pose::theta_deg), (std::set<double>{10, 15, 20}));
  EXPECT_EQ(recipe.sweep.bracket.t_meas_ms[0] - recipe.sweep.bracket.t_ref_ms, 27.0);
  std::map<std::pair<double, double>, std::set<double>> per_pose;
  double sum = 0.0;
  for (const Pose& p : plan.poses) {
    per_pose[{p.slide_mm, p.theta_deg}].insert(p.bias_ma);
    sum += p.bias_ma;
  }
  ASSERT_EQ(per_pose.size(), 9u);
  for (const auto& [pose, currents] : per_pose) EXPECT_EQ(currents.size(), 10u);
  EXPECT_EQ(Distinct(plan, &Pose::bias_ma).size(), 90u);  // fresh draws at each pose
  EXPECT_NEAR(sum / 90.0, 500.0, 4.0 * 50.0 / std::sqrt(90.0));
  ExpectWithinLimits(recipe, plan);
}

TEST(RecipeTest, ConsistencyRepeatsOneHundredTimes) {
  const Recipe recipe = Shipped("consistency.yaml");
  const Plan plan = PlanRecipe(recipe);
  EXPECT_EQ(plan.summary.pose_count, 400);
  EXPECT_EQ(plan.summary.frame_count, 800);
  EXPECT_EQ(plan.summary.difference_count, 400);
  EXPECT_EQ(Distinct(plan, &Pose::slide_mm), (std::set<double>{2700}));
  EXPECT_EQ(Distinct(plan, &Pose::theta_deg), (std::set<double>{0, 10, 20, 30}));
  EXPECT_EQ(plan.summary.moves, 4);  // the repetitions do not move the station
  std::map<double, int> per_angle;
  for (const Pose& p : plan.poses) ++per_angle[p.theta_deg];
  for (const auto& [theta, count] : per_angle) EXPECT_EQ(count, 100) << theta;
}

TEST(RecipeTest, ConsistencyBracketTakesTheTable3ExposuresEachRepetition) {
  const Recipe recipe = Shipped("consistency-bracket.yaml");
  const Recipe table3 = Shipped("table3-calibration.yaml");
  const Plan plan = PlanRecipe(recipe);
  EXPECT_EQ(plan.summary.pose_count, 400);
  EXPECT_EQ(plan.summary.frame_count, 2000);
  EXPECT_EQ(plan.summary.difference_count, 1600);
  EXPECT_EQ(plan.summary.moves, 4);
  // Exposures inside the calibration's: no estimate extrapolates in t.
  EXPECT_EQ(recipe.sweep.bracket.t_meas_ms, table3.sweep.bracket.t_meas_ms);
  EXPECT_EQ(recipe.sweep.bracket.t_ref_ms, table3.sweep.bracket.t_ref_ms);
  EXPECT_EQ(recipe.after, AfterRecording::kEstimate);
}

TEST(RecipeTest, Table3ThriceIsTable3sPosesEachBracketedThreeTimesWithoutMoving) {
  const Recipe recipe = Shipped("table3-calibration-x3.yaml");
  const Recipe table3 = Shipped("table3-calibration.yaml");
  EXPECT_EQ(recipe.after, AfterRecording::kFit);
  EXPECT_EQ(recipe.rig.name, table3.rig.name);
  const Plan plan = PlanRecipe(recipe), once = PlanRecipe(table3);
  EXPECT_EQ(plan.summary.pose_count, 3 * once.summary.pose_count);
  EXPECT_EQ(plan.summary.frame_count, 960);
  EXPECT_EQ(plan.summary.difference_count, 768);
  EXPECT_EQ(plan.summary.moves, once.summary.moves);  // the repeats never move the station
  EXPECT_EQ(recipe.sweep.bracket.t_meas_ms, table3.sweep.bracket.t_meas_ms);
  EXPECT_EQ(recipe.sweep.bracket.t_ref_ms, table3.sweep.bracket.t_ref_ms);
  std::map<std::vector<double>, int> brackets;
  for (const Pose& p : plan.poses) ++brackets[{p.slide_mm, p.theta_deg, p.bias_ma}];
  std::set<std::vector<double>> grid;
  for (const Pose& p : once.poses) grid.insert({p.slide_mm, p.theta_deg, p.bias_ma});
  EXPECT_EQ(brackets.size(), grid.size());
  for (const auto& [pose, count] : brackets) {
    EXPECT_EQ(count, 3);
    EXPECT_TRUE(grid.count(pose)) << pose[0] << " mm, " << pose[1] << " deg, " << pose[2] << " mA";
  }
  ExpectWithinLimits(recipe, plan);
}

TEST(RecipeTest, SmokeCalibrationIsSmall) {
  const Recipe recipe = Shipped("smoke-calibration.yaml");
  const Plan plan = PlanRecipe(recipe);
  EXPECT_EQ(plan.summary.pose_count, 24);
  EXPECT_EQ(plan.summary.frame_count, 96);
  EXPECT_EQ(plan.summary.difference_count, 72);
  EXPECT_EQ(recipe.after, AfterRecording::kFit);
}

TEST(RecipeTest, DefaultsOfOptionalKeys) {
  const Recipe recipe = ParseRecipe(R"(axes:
  slide_mm: 2000
  pan_deg: [0, 10]
  bias_ma: 500
bracket:
  t_ref_ms: 8
  t_meas_ms: 30
)",
                                    "/some/where/minimal.yaml", kRecipes);
  EXPECT_EQ(recipe.name, "minimal");
  EXPECT_EQ(recipe.output_dir, "runs/minimal");
  EXPECT_EQ(recipe.after, AfterRecording::kNone);
  EXPECT_EQ(recipe.rig.name, "virtual");
  EXPECT_EQ(recipe.sweep.angle_mode, AngleMode::kPan);
  EXPECT_EQ(recipe.sweep.tilt_deg.values, (std::vector<double>{0.0}));
  EXPECT_EQ(recipe.sweep.bracket.repeats, 1);
  EXPECT_FALSE(recipe.sweep.bracket.retake_reference);
  EXPECT_EQ(recipe.sweep.settle.after_move_ms, SettleSpec().after_move_ms);
  EXPECT_EQ(recipe.camera_response, CameraResponse::kLinear);
  std::string why;
  EXPECT_TRUE(recipe.sweep.IsValid(&why)) << why;
}

TEST(RecipeTest, OrderSerpentineSettleAndRangesAreRead) {
  const Recipe recipe = ParseRecipe(R"(name: custom
rig: rigs/virtual.yaml
output: /tmp/x
after: estimate
axes:
  slide_mm: {start: 1000, stop: 1600, step: 300}
  theta_deg: {start: 30, stop: 0, step: -15}
  tilt_deg: [0]
  bias_ma: [450, 500]
order: [bias_ma, theta_deg]
serpentine: false
bracket:
  t_ref_ms: 8.5
  t_meas_ms: {start: 30, stop: 31.5, step: 0.5}
  repeats: 2
  retake_reference: yes
settle:
  after_move_ms: 0
  after_current_ms: 2000
)",
                                    "custom.yaml", kRecipes);
  EXPECT_EQ(recipe.output_dir, "/tmp/x");
  EXPECT_EQ(recipe.sweep.slide_mm.values, (std::vector<double>{1000, 1300, 1600}));
  EXPECT_EQ(recipe.sweep.angle_deg.values, (std::vector<double>{30, 15, 0}));
  EXPECT_EQ(recipe.sweep.bracket.t_meas_ms, (std::vector<double>{30, 30.5, 31, 31.5}));
  EXPECT_EQ(recipe.sweep.bracket.repeats, 2);
  EXPECT_TRUE(recipe.sweep.bracket.retake_reference);
  EXPECT_EQ(recipe.sweep.settle.after_current_ms, 2000.0);
  EXPECT_TRUE(recipe.sweep.serpentine.empty());
  ASSERT_EQ(recipe.sweep.order.size(), 4u);
  EXPECT_EQ(recipe.sweep.order[0], SweepAxis::kBias);
  EXPECT_EQ(recipe.sweep.order[1], SweepAxis::kAngle);
  const Plan plan = PlanRecipe(recipe);
  EXPECT_EQ(plan.poses.front().bias_ma, 450.0);
  EXPECT_EQ(plan.poses.back().bias_ma, 500.0);
  EXPECT_EQ(plan.summary.frame_count, 2 * 3 * 3 * 2 * 8);
}

TEST(RecipeTest, RangesAreIntegerSafe) {
  // 0.1 steps accumulate rounding errors when summed; the range must still end exactly at stop.
  const Recipe recipe = ParseRecipe(R"(axes:
  slide_mm: {start: 1000, stop: 1001, step: 0.1}
  theta_deg: 0
  bias_ma: 500
bracket: {t_ref_ms: 8, t_meas_ms: 30}
)",
                                    "ranges.yaml", kRecipes);
  const std::vector<double>& v = recipe.sweep.slide_mm.values;
  ASSERT_EQ(v.size(), 11u);
  EXPECT_EQ(v.front(), 1000.0);
  EXPECT_EQ(v.back(), 1001.0);
  for (size_t i = 0; i < v.size(); ++i) EXPECT_NEAR(v[i], 1000.0 + 0.1 * i, 1e-9);
}

TEST(RecipeTest, CalibrationCameraResponseIsRead) {
  const char* text = R"(after: fit
calibration:
  camera_response: recover
axes:
  slide_mm: 2000
  pan_deg: [0, 10]
  bias_ma: 500
bracket:
  t_ref_ms: 8
  t_meas_ms: 30
)";
  const Recipe recipe = ParseRecipe(text, "/some/where/recover.yaml", kRecipes);
  EXPECT_EQ(recipe.camera_response, CameraResponse::kRecover);
  EXPECT_EQ(CameraResponseName(recipe.camera_response), "recover");
  // The same key from a recording's copy of the recipe, without its rig.
  EXPECT_EQ(CameraResponseOfRecipeText(text, "r.yaml"), CameraResponse::kRecover);
  EXPECT_EQ(CameraResponseOfRecipeText("calibration: {camera_response: linear}\n", "r.yaml"),
            CameraResponse::kLinear);
  EXPECT_EQ(CameraResponseOfRecipeText("name: x\n", "r.yaml"), CameraResponse::kLinear);
  try {
    CameraResponseOfRecipeText("name: x\ncalibration:\n  camera_response: gamma\n", "r.yaml");
    FAIL() << "accepted camera_response: gamma";
  } catch (const RecipeError& e) {
    EXPECT_EQ(e.Line(), 3) << e.what();
    EXPECT_NE(e.Message().find("valid: linear"), std::string::npos) << e.what();
  }
}

// A recipe that the table below breaks in one place each.
struct BadRecipe {
  const char* what;
  const char* text;
  int line;
  int column;
  const char* message;  // a substring of the error
};

const BadRecipe kBadRecipes[] = {
    {"unknown top-level key", R"(name: t
axes:
  slide_mm: [1500, 2000]
  theta_deg: [0, 10]
  bias_ma: [475, 500]
bracket:
  t_ref_ms: 8
  t_meas_ms: [30, 32]
colour: red
)",
     9, 1, "unknown key 'colour' in the recipe; valid keys: name, description"},
    {"unknown axis with a suggestion", R"(name: t
axes:
  slide: [1500, 2000]
  theta_deg: [0, 10]
  bias_ma: [475, 500]
bracket:
  t_ref_ms: 8
  t_meas_ms: [30, 32]
)",
     3, 3, "did you mean 'slide_mm'?"},
    {"wrong type", R"(name: t
axes:
  slide_mm: far
  theta_deg: [0, 10]
  bias_ma: [475, 500]
bracket:
  t_ref_ms: 8
  t_meas_ms: [30, 32]
)",
     3, 13, "axes.slide_mm must be a number, not 'far'"},
    {"wrong type in a list", R"(name: t
axes:
  slide_mm: [1500, far]
  theta_deg: [0, 10]
  bias_ma: [475, 500]
bracket:
  t_ref_ms: 8
  t_meas_ms: [30, 32]
)",
     3, 20, "must be a number"},
    {"outside the rig's limits", R"(name: t
axes:
  slide_mm: [1500, 4000]
  theta_deg: [0, 10]
  bias_ma: [475, 500]
bracket:
  t_ref_ms: 8
  t_meas_ms: [30, 32]
)",
     3, 20, "axes.slide_mm 4000 is outside the rig's limits [1000, 3500]"},
    {"empty axis", R"(name: t
axes:
  slide_mm: [1500, 2000]
  theta_deg: [0, 10]
  bias_ma: []
bracket:
  t_ref_ms: 8
  t_meas_ms: [30, 32]
)",
     5, 12, "axes.bias_ma is empty"},
    {"range that misses its stop", R"(name: t
axes:
  slide_mm: [1500, 2000]
  theta_deg: {start: 0, stop: 36, step: 5}
  bias_ma: [475, 500]
bracket:
  t_ref_ms: 8
  t_meas_ms: [30, 32]
)",
     4, 31, "valid stops: 35 or 40"},
    {"range with a zero step", R"(name: t
axes:
  slide_mm: [1500, 2000]
  theta_deg: {start: 0, stop: 35, step: 0}
  bias_ma: [475, 500]
bracket:
  t_ref_ms: 8
  t_meas_ms: [30, 32]
)",
     4, 41, "step must not be 0"},
    {"range stepping away from its stop", R"(name: t
axes:
  slide_mm: [1500, 2000]
  theta_deg: {start: 0, stop: 35, step: -5}
  bias_ma: [475, 500]
bracket:
  t_ref_ms: 8
  t_meas_ms: [30, 32]
)",
     4, 41, "use step 5"},
    {"range with a missing key", R"(name: t
axes:
  slide_mm: {start: 1500, stop: 2000}
  theta_deg: [0, 10]
  bias_ma: [475, 500]
bracket:
  t_ref_ms: 8
  t_meas_ms: [30, 32]
)",
     3, 13, "missing the key 'step'"},
    {"missing bracket", R"(name: t
axes:
  slide_mm: [1500, 2000]
  theta_deg: [0, 10]
  bias_ma: [475, 500]
)",
     1, 1, "the recipe is missing the key 'bracket'"},
    {"missing t_meas_ms", R"(name: t
axes:
  slide_mm: [1500, 2000]
  theta_deg: [0, 10]
  bias_ma: [475, 500]
bracket:
  t_ref_ms: 8
)",
     7, 3, "bracket is missing the key 't_meas_ms'"},
    {"missing bias axis", R"(name: t
axes:
  slide_mm: [1500, 2000]
  theta_deg: [0, 10]
bracket:
  t_ref_ms: 8
  t_meas_ms: [30, 32]
)",
     3, 3, "axes is missing the key 'bias_ma'"},
    {"measurement exposure not longer than the reference", R"(name: t
axes:
  slide_mm: [1500, 2000]
  theta_deg: [0, 10]
  bias_ma: [475, 500]
bracket:
  t_ref_ms: 8
  t_meas_ms: [30, 6]
)",
     8, 19, "must be longer than t_ref_ms 8"},
    {"not a boolean", R"(name: t
axes:
  slide_mm: [1500, 2000]
  theta_deg: [0, 10]
  bias_ma: [475, 500]
bracket:
  t_ref_ms: 8
  t_meas_ms: [30, 32]
  retake_reference: maybe
)",
     9, 21, "must be true or false"},
    {"repeats not whole", R"(name: t
axes:
  slide_mm: [1500, 2000]
  theta_deg: [0, 10]
  bias_ma: [475, 500]
bracket:
  t_ref_ms: 8
  t_meas_ms: [30, 32]
  repeats: 2.5
)",
     9, 12, "must be a whole number"},
    {"theta and pan both", R"(name: t
axes:
  slide_mm: [1500, 2000]
  theta_deg: [0, 10]
  pan_deg: [0]
  bias_ma: [475, 500]
bracket:
  t_ref_ms: 8
  t_meas_ms: [30, 32]
)",
     5, 12, "either theta_deg or pan_deg"},
    {"theta below the tilt", R"(name: t
axes:
  slide_mm: [1500, 2000]
  theta_deg: [0, 10]
  tilt_deg: 5
  bias_ma: [475, 500]
bracket:
  t_ref_ms: 8
  t_meas_ms: [30, 32]
)",
     4, 15, "needs |theta| >= |tilt|"},
    {"theta beyond the pan limits", R"(name: t
axes:
  slide_mm: [1500, 2000]
  theta_deg: [0, 50]
  bias_ma: [475, 500]
bracket:
  t_ref_ms: 8
  t_meas_ms: [30, 32]
)",
     4, 18, "outside the rig's pan limits [-45, 45]"},
    {"random mean outside the limits", R"(name: t
axes:
  slide_mm: [1500, 2000]
  theta_deg: [0, 10]
  bias_ma: {mean: 700, sd: 50, count: 10, seed: 1}
bracket:
  t_ref_ms: 8
  t_meas_ms: [30, 32]
)",
     5, 19, "axes.bias_ma.mean 700 is outside the rig's limits [0, 600]"},
    {"random draws without a seed", R"(name: t
axes:
  slide_mm: [1500, 2000]
  theta_deg: [0, 10]
  bias_ma: {mean: 500, sd: 50, count: 10}
bracket:
  t_ref_ms: 8
  t_meas_ms: [30, 32]
)",
     5, 12, "is missing the key 'seed'"},
    {"unknown rig", R"(name: t
rig: nowhere
axes:
  slide_mm: [1500, 2000]
  theta_deg: [0, 10]
  bias_ma: [475, 500]
bracket:
  t_ref_ms: 8
  t_meas_ms: [30, 32]
)",
     2, 6, "rig 'nowhere' not found"},
    {"duplicate key", R"(name: t
axes:
  slide_mm: [1500, 2000]
  theta_deg: [0, 10]
  bias_ma: [475, 500]
  slide_mm: [1500]
bracket:
  t_ref_ms: 8
  t_meas_ms: [30, 32]
)",
     6, 3, "key 'slide_mm' appears twice in axes"},
    {"order names an axis the recipe does not have", R"(name: t
axes:
  slide_mm: [1500, 2000]
  theta_deg: [0, 10]
  bias_ma: [475, 500]
order: [slide_mm, pan_deg]
bracket:
  t_ref_ms: 8
  t_meas_ms: [30, 32]
)",
     6, 19, "'pan_deg' is not an axis of this recipe; valid: slide_mm, theta_deg"},
    {"unknown after", R"(name: t
after: celebrate
axes:
  slide_mm: [1500, 2000]
  theta_deg: [0, 10]
  bias_ma: [475, 500]
bracket:
  t_ref_ms: 8
  t_meas_ms: [30, 32]
)",
     2, 8, "valid: fit (calibration), estimate (validation), none"},
    {"axes not a map", R"(name: t
axes: [1500, 2000]
bracket:
  t_ref_ms: 8
  t_meas_ms: [30, 32]
)",
     2, 7, "axes must be a map with keys slide_mm, theta_deg, pan_deg, tilt_deg, bias_ma"},
    {"unknown camera response", R"(name: t
calibration:
  camera_response: curved
axes:
  slide_mm: [1500, 2000]
  theta_deg: [0, 10]
  bias_ma: [475, 500]
bracket:
  t_ref_ms: 8
  t_meas_ms: [30, 32]
)",
     3, 20, "calibration.camera_response 'curved' is not known; valid: linear (default), recover"},
    {"unknown calibration key", R"(name: t
calibration:
  response: recover
axes:
  slide_mm: [1500, 2000]
  theta_deg: [0, 10]
  bias_ma: [475, 500]
bracket:
  t_ref_ms: 8
  t_meas_ms: [30, 32]
)",
     3, 3, "unknown key 'response' in calibration"},
    {"YAML syntax error", R"(name: t
axes:
  slide_mm: [1500, 2000
  theta_deg: [0, 10]
)",
     0, 0, "YAML syntax error"},
};

TEST(RecipeTest, BadRecipesNameTheirLineAndColumn) {
  for (const BadRecipe& bad : kBadRecipes) {
    SCOPED_TRACE(bad.what);
    try {
      ParseRecipe(bad.text, "bad.yaml", kRecipes);
      ADD_FAILURE() << "no error for: " << bad.what;
    } catch (const RecipeError& e) {
      EXPECT_EQ(e.File(), "bad.yaml");
      if (bad.line > 0) {
        EXPECT_EQ(e.Line(), bad.line) << e.what();
        EXPECT_EQ(e.Column(), bad.column) << e.what();
        const std::string prefix =
            "bad.yaml:" + std::to_string(bad.line) + ":" + std::to_string(bad.column) + ": ";
        EXPECT_EQ(std::string(e.what()).rfind(prefix, 0), 0u) << e.what();
      } else {
        EXPECT_GT(e.Line(), 0) << e.what();
      }
      EXPECT_NE(e.Message().find(bad.message), std::string::npos) << e.what();
    }
  }
}

TEST(RecipeTest, MissingFileIsARecipeError) {
  try {
    LoadRecipe("/nonexistent/recipe.yaml");
    FAIL() << "no error";
  } catch (const RecipeError& e) {
    EXPECT_EQ(e.File(), "/nonexistent/recipe.yaml");
    EXPECT_EQ(e.Line(), 0);
    EXPECT_NE(std::string(e.what()).find("cannot open"), std::string::npos);
  }
}

TEST(RecipeTest, ErrorsInTheRigFileNameTheRigFile) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("irdist_recipe_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir / "rigs");
  {
    std::ofstream rig(dir / "rigs" / "narrow.yaml");
    rig << "kind: virtual\nstation:\n  limits:\n    slide_mm: [1000, 1800]\n    bogus: 1\n";
  }
  {
    std::ofstream recipe(dir / "r.yaml");
    recipe << "rig: narrow\naxes: {slide_mm: 1500, theta_deg: 0, bias_ma: 500}\n"
              "bracket: {t_ref_ms: 8, t_meas_ms: 30}\n";
  }
  try {
    LoadRecipe((dir / "r.yaml").string());
    FAIL() << "no error";
  } catch (const RecipeError& e) {
    EXPECT_EQ(e.File(), (dir / "rigs" / "narrow.yaml").string());
    EXPECT_EQ(e.Line(), 5);
    EXPECT_EQ(e.Column(), 5);
  }
  // With the rig fixed, its narrower limits apply to the recipe.
  {
    std::ofstream rig(dir / "rigs" / "narrow.yaml");
    rig << "kind: virtual\nstation:\n  limits:\n    slide_mm: [1000, 1800]\n";
  }
  {
    std::ofstream recipe(dir / "r.yaml");
    recipe << "rig: narrow\naxes: {slide_mm: [1500, 2000], theta_deg: 0, bias_ma: 500}\n"
              "bracket: {t_ref_ms: 8, t_meas_ms: 30}\n";
  }
  try {
    LoadRecipe((dir / "r.yaml").string());
    FAIL() << "no error";
  } catch (const RecipeError& e) {
    EXPECT_EQ(e.File(), (dir / "r.yaml").string());
    EXPECT_EQ(e.Line(), 2);
    EXPECT_NE(e.Message().find("[1000, 1800]"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

TEST(RecipeTest, FindRigFileLooksBesideTheRecipeThenInTheSourceTree) {
  EXPECT_EQ(FindRigFile("virtual", kRecipes),
            std::filesystem::path(kRecipes + "/rigs/virtual.yaml").lexically_normal().string());
  EXPECT_FALSE(FindRigFile("virtual", "/nonexistent").empty());  // falls back to the source tree
  EXPECT_EQ(FindRigFile("no-such-rig", kRecipes), "");
  EXPECT_EQ(FindRigFile("rigs/virtual.yaml", "/nonexistent"), "");  // paths: relative to base
}


// Sizes that would not fit in memory are refused while the recipe is read, with the numbers.
TEST(RecipeSafety, PlansTooLargeForMemoryAreRefusedWithTheirNumbers) {
  const std::string repeats = R"(axes:
  slide_mm: 2000
  pan_deg: 0
  bias_ma: 500
bracket:
  t_ref_ms: 8
  t_meas_ms: 30
  repeats: 2000000000
)";
  try {
    ParseRecipe(repeats, "big.yaml", kRecipes);
    FAIL() << "2e9 repeats accepted";
  } catch (const RecipeError& e) {
    EXPECT_EQ(e.File(), "big.yaml");
    EXPECT_NE(std::string(e.what()).find("asks for 2000000000 brackets"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("repeats 2000000000"), std::string::npos) << e.what();
  }
  const std::string grid = R"(axes:
  slide_mm: {start: 1000, stop: 2999.98, step: 0.02}
  pan_deg: {start: -20, stop: 19.9996, step: 0.0004}
  bias_ma: 500
bracket:
  t_ref_ms: 8
  t_meas_ms: 30
)";
  try {
    ParseRecipe(grid, "grid.yaml", kRecipes);
    FAIL() << "a 1e5 x 1e5 grid accepted";
  } catch (const RecipeError& e) {
    EXPECT_NE(std::string(e.what()).find("slide 100000 x angle 100000"), std::string::npos)
        << e.what();
  }
}

// A recipe error for `text` (read as bounded.yaml); fails the test when there is none.
RecipeError BoundedError(const std::string& text) {
  try {
    ParseRecipe(text, "bounded.yaml", kRecipes);
  } catch (const RecipeError& e) {
    return e;
  }
  ADD_FAILURE() << "accepted:\n" << text;
  return RecipeError("", 0, 0, "");
}

std::string WithBias(const std::string& bias) {
  return "axes:\n  slide_mm: 2000\n  pan_deg: 0\n  bias_ma: " + bias +
         "\nbracket:\n  t_ref_ms: 8\n  t_meas_ms: 30\n";
}

// Random draws that (almost) never land in their window are refused at the sd's line with the
// largest sd that would do, instead of redrawing for ever.
TEST(RecipeSafety, RandomDrawsThatCannotMeetTheirWindowNameTheSdAndTheFix) {
  for (const std::string& draws :
       {std::string("{mean: 500, sd: 1e308, count: 3, seed: 1}"),
        std::string("{mean: 500, sd: 50, count: 3, seed: 1, min: 500, max: 500.0000001}")}) {
    SCOPED_TRACE(draws);
    const RecipeError e = BoundedError(WithBias(draws));
    EXPECT_EQ(e.File(), "bounded.yaml");
    EXPECT_EQ(e.Line(), 4) << e.what();
    EXPECT_NE(e.Message().find("lower sd to at most"), std::string::npos) << e.what();
  }
  // The sd it suggests is accepted.
  const Recipe ok = ParseRecipe(WithBias("{mean: 500, sd: 3e-9, count: 3, seed: 1, min: 500, "
                                         "max: 500.0000001}"),
                                "bounded.yaml", kRecipes);
  EXPECT_EQ(PlanRecipe(ok).summary.pose_count, 3);
}

TEST(RecipeSafety, HugeSettlesAndExposuresAreRefusedAtTheirLine) {
  const std::string base = WithBias("500");
  const RecipeError settle = BoundedError(base + "settle:\n  after_move_ms: 1e308\n");
  EXPECT_EQ(settle.Line(), 9) << settle.what();
  EXPECT_NE(settle.Message().find("settle.after_move_ms 1e+308 must lie in [0, 3600000] ms"),
            std::string::npos)
      << settle.what();
  const RecipeError meas = BoundedError(
      "axes: {slide_mm: 2000, pan_deg: 0, bias_ma: 500}\nbracket:\n  t_ref_ms: 8\n"
      "  t_meas_ms: [30, 1e308]\n");
  EXPECT_EQ(meas.Line(), 4) << meas.what();
  EXPECT_NE(meas.Message().find("(t_ref_ms, 100000] ms"), std::string::npos) << meas.what();
  const RecipeError ref = BoundedError(
      "axes: {slide_mm: 2000, pan_deg: 0, bias_ma: 500}\nbracket:\n  t_ref_ms: 1e308\n"
      "  t_meas_ms: 2e308\n");
  EXPECT_EQ(ref.Line(), 3) << ref.what();
}

// 50000 poses x 42951 frames overflowed the int frame count (a negative count was printed).
TEST(RecipeSafety, FrameCountsBeyondTheLimitAreRefusedNotWrapped) {
  const RecipeError e = BoundedError(
      "axes:\n  slide_mm: {start: 1000, stop: 3499.95, step: 0.05}\n  pan_deg: 0\n"
      "  bias_ma: 500\nbracket:\n  t_ref_ms: 1\n"
      "  t_meas_ms: {start: 1.002, stop: 86.9, step: 0.002}\n");
  EXPECT_NE(e.Message().find("slide 50000 x angle 1"), std::string::npos) << e.what();
  EXPECT_NE(e.Message().find("2147550000 frames"), std::string::npos) << e.what();  // > 2^31
}

// A rig path that names a file that is no rig file: its text never shows in the error.
TEST(RecipeSafety, ARigThatIsNotARigFileIsNotEchoed) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("irdist_recipe_passwd_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  {
    std::ofstream passwd(dir / "passwd");
    passwd << "root:x:0:0:root:/root:/bin/bash\nsecret:x:1000:1000::/home/secret:/bin/sh\n";
  }
  try {
    ParseRecipe("rig: " + (dir / "passwd").string() + "\n" + WithBias("500"), "r.yaml",
                dir.string());
    ADD_FAILURE() << "a passwd file accepted as a rig";
  } catch (const RecipeError& e) {
    EXPECT_EQ(e.File(), (dir / "passwd").string());
    EXPECT_EQ(std::string(e.what()).find("root:x"), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).find("secret"), std::string::npos) << e.what();
    EXPECT_NE(e.Message().find("must be a map"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

// A rig whose motion is absurdly slow: the plan's duration would overflow; refused naming the rig.
TEST(RecipeSafety, APlanLongerThanAnyLabIsRefusedNamingTheRigFile) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("irdist_recipe_slow_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir / "rigs");
  {
    std::ofstream rig(dir / "rigs" / "slow.yaml");
    rig << "kind: virtual\nstation:\n  motion:\n    slide: {speed: 1e-300, acceleration: 1e-300}\n";
  }
  Recipe recipe = ParseRecipe(
      "rig: slow\naxes: {slide_mm: [1500, 2000], pan_deg: 0, bias_ma: 500}\n"
      "bracket: {t_ref_ms: 8, t_meas_ms: 30}\n",
      "slow-recipe.yaml", dir.string());
  try {
    PlanRecipe(recipe);
    ADD_FAILURE() << "an endless plan accepted";
  } catch (const RecipeError& e) {
    EXPECT_EQ(e.File(), "slow-recipe.yaml");
    EXPECT_NE(e.Message().find("over 1e9 s"), std::string::npos) << e.what();
    EXPECT_NE(e.Message().find(recipe.rig_path), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

// On a rig whose pan and tilt limits reach beyond 90 deg, random angles without their own window
// would be drawn where the IRED faces away (and a tilt of -1.4e9 deg made a plan of NaN seconds):
// refused at the axis's line with the fix; with min and max inside (-90, 90) it plans.
TEST(RecipeSafety, RandomAnglesDrawnBeyondNinetyDegreesAreRefusedAtTheirLine) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("irdist_recipe_wide_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir / "rigs");
  {
    std::ofstream rig(dir / "rigs" / "wide.yaml");
    rig << "kind: virtual\nstation:\n  limits:\n    pan_deg: [-170, 170]\n"
           "    tilt_deg: [-170, 170]\n";
  }
  const std::string head = "rig: wide\naxes:\n  slide_mm: [1500, 2000]\n  bias_ma: 500\n";
  const std::string bracket = "bracket: {t_ref_ms: 8, t_meas_ms: 30}\n";
  try {
    ParseRecipe(head + "  pan_deg: {mean: 0, sd: 20, count: 3, seed: 1}\n" + bracket,
                "wide-recipe.yaml", dir.string());
    ADD_FAILURE() << "random pan drawn over [-170, 170] accepted";
  } catch (const RecipeError& e) {
    EXPECT_EQ(e.File(), "wide-recipe.yaml");
    EXPECT_EQ(e.Line(), 5) << e.what();
    EXPECT_NE(e.Message().find("axes.pan_deg"), std::string::npos) << e.what();
    EXPECT_NE(e.Message().find("inside (-90, 90) deg"), std::string::npos) << e.what();
  }
  const Recipe recipe = ParseRecipe(
      head + "  pan_deg: {mean: 0, sd: 20, count: 3, seed: 1, min: -60, max: 60}\n" + bracket,
      "wide-recipe.yaml", dir.string());
  EXPECT_EQ(PlanRecipe(recipe).poses.size(), 6u);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace irdist
