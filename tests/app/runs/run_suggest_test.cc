// plan --suggest's probe run: the probe recipe it records (the recipe's two ends crossed, at its
// reference and its longest measurement exposure) read back as a recipe, and the refusals before
// anything is swept. The suggestion's arithmetic is tested in suggest_test.cc, a folder name YAML
// would misread and a bad --from in run_test.cc, the whole probe run in
// tests/integration/suggest_test.cc.
#include "app/runs/run_suggest.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <tuple>

#include "app/inputs/recipe.h"
#include "station/plan.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;

class RunSuggestTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("irdist-run-suggest-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // A recipe on the virtual rig with these axes and bracket lines (YAML, two-space indented).
  Recipe Write(const std::string& axes, const std::string& bracket) {
    const fs::path path = dir_ / "recipe.yaml";
    std::ofstream(path) << "name: bench\nrig: " << IRDIST_SOURCE_DIR
                        << "/recipes/rigs/virtual.yaml\nafter: fit\naxes:\n" << axes
                        << "bracket:\n" << bracket;
    return LoadRecipe(path.string());
  }

  // The probe recipe of `recipe`, written beside it and loaded back as a run would load it.
  Recipe Probe(const Recipe& recipe, std::string* text = nullptr) {
    const std::string probe = SuggestProbeRecipe(recipe, PlanRecipe(recipe));
    if (text != nullptr) *text = probe;
    std::ofstream(dir_ / "probe-recipe.yaml") << probe;
    return LoadRecipe((dir_ / "probe-recipe.yaml").string());
  }

  fs::path dir_;
};

using PoseKey = std::tuple<long, long, long>;  // slide, |theta|, current, in 0.01 units
std::multiset<PoseKey> PosesOf(const Plan& plan) {
  std::multiset<PoseKey> poses;
  for (const Pose& p : plan.poses) {
    poses.insert({std::lround(p.slide_mm * 100), std::lround(std::abs(p.theta_deg) * 100),
                  std::lround(p.bias_ma * 100)});
  }
  return poses;
}

// The bright end (nearest, smallest |theta|, highest current) and the faint end (farthest,
// largest |theta|, lowest current), each axis's two ends crossed: 8 poses, each once, whatever
// the recipe's inner values, order or repeats; theta -20 deg is 20 deg from the axis.
TEST_F(RunSuggestTest, TheProbeCrossesTheRecipesEndsOnEveryAxis) {
  const Recipe recipe = Write(
      "  slide_mm: [2000, 1500, 3000]\n  theta_deg: [-20, 0, 10]\n  bias_ma: [475, 450, 500]\n",
      "  t_ref_ms: 8\n  t_meas_ms: [30, 36, 33]\n  repeats: 3\n");
  const Plan probe = PlanRecipe(Probe(recipe));
  std::multiset<PoseKey> expected;
  for (long slide : {1500, 3000}) {
    for (long theta : {0, 20}) {
      for (long ma : {450, 500}) expected.insert({slide * 100, theta * 100, ma * 100});
    }
  }
  EXPECT_EQ(PosesOf(probe), expected);
}

// Each probe bracket is the recipe's reference and its longest measurement exposure: the
// longest is the one nearest saturation at the bright end and the faintest signal at the other.
TEST_F(RunSuggestTest, TheProbeTakesTheReferenceAndTheLongestMeasurementExposure) {
  const Recipe recipe =
      Write("  slide_mm: [1500, 3000]\n  theta_deg: [0, 30]\n  bias_ma: [475, 500]\n",
            "  t_ref_ms: 6.5\n  t_meas_ms: [30, 41.25, 33]\n");
  const Recipe probe = Probe(recipe);
  EXPECT_DOUBLE_EQ(probe.sweep.bracket.t_ref_ms, 6.5);
  EXPECT_EQ(probe.sweep.bracket.t_meas_ms, std::vector<double>{41.25});
}

// An axis with one value stays one value: one current gives 4 poses, one distance and one
// current 2.
TEST_F(RunSuggestTest, AnAxisWithOneValueIsNotDoubled) {
  Recipe recipe = Write("  slide_mm: [1500, 3000]\n  theta_deg: [0, 30]\n  bias_ma: [490]\n",
                        "  t_ref_ms: 8\n  t_meas_ms: [30]\n");
  Plan probe = PlanRecipe(Probe(recipe));
  EXPECT_EQ(probe.poses.size(), 4u);
  for (const Pose& p : probe.poses) EXPECT_DOUBLE_EQ(p.bias_ma, 490.0);
  recipe = Write("  slide_mm: [2200]\n  theta_deg: [0, 30]\n  bias_ma: [490]\n",
                 "  t_ref_ms: 8\n  t_meas_ms: [30]\n");
  probe = PlanRecipe(Probe(recipe));
  EXPECT_EQ(probe.poses.size(), 2u);
}

// The probe is a recipe of its own: named after the recipe, on the same rig file (by absolute
// path: the probe lives in another folder), no fit after it, and it says what it is for.
TEST_F(RunSuggestTest, TheProbeIsARecipeOfItsOwnOnTheSameRig) {
  const Recipe recipe =
      Write("  slide_mm: [1500, 3000]\n  theta_deg: [0, 30]\n  bias_ma: [475, 500]\n",
            "  t_ref_ms: 8\n  t_meas_ms: [30, 36]\n");
  std::string text;
  const Recipe probe = Probe(recipe, &text);
  EXPECT_EQ(probe.name, "bench-probe");
  EXPECT_TRUE(fs::path(probe.rig_path).is_absolute()) << probe.rig_path;
  EXPECT_TRUE(fs::equivalent(probe.rig_path, recipe.rig_path)) << text;
  EXPECT_EQ(probe.after, AfterRecording::kNone) << text;
  EXPECT_NE(text.find("irdist plan --suggest " + recipe.path), std::string::npos) << text;
}

// A recipe that cannot be read is refused before anything starts: no probe folder is made.
TEST_F(RunSuggestTest, AnUnreadableRecipeIsRefusedBeforeTheProbeFolderIsMade) {
  PlanArgs args;
  args.recipe = (dir_ / "no-such-recipe.yaml").string();
  args.suggest = true;
  args.out_dir = (dir_ / "probe").string();
  std::ostringstream out, err;
  try {
    RunSuggest(args, {out, err});
    ADD_FAILURE() << "accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(args.recipe), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir_ / "probe"));
}

}  // namespace
}  // namespace irdist
