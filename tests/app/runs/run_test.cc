// The live runs: the probe recipe of plan --suggest, a run folder holding another run's results,
// a bad --from refused before the probe.
#include "app/runs/run.h"
#include "app/runs/run_suggest.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include <string>

#include "app/inputs/command_args.h"
#include "app/inputs/errors.h"
#include "app/inputs/recipe.h"
#include "station/plan.h"

namespace irdist {
namespace {

// The case: a lab folder named `lab #2` (a '#' starts a YAML comment when unquoted) and
// a recipe name with ': '. The probe recipe reads back with the same rig file and the ends.
TEST(SuggestProbeRecipeTest, ReadsBackFromAFolderWhoseNameYamlWouldMisread) {
  namespace fs = std::filesystem;
  const fs::path dir =
      fs::temp_directory_path() / ("irdist-probe-" + std::to_string(::getpid())) / "lab #2";
  fs::create_directories(dir / "rigs");
  fs::copy_file(fs::path(IRDIST_SOURCE_DIR) / "recipes/rigs/virtual.yaml", dir / "rigs/my rig.yaml",
                fs::copy_options::overwrite_existing);
  std::ofstream(dir / "recipe.yaml")
      << "name: \"bench: #2\"\nrig: \"rigs/my rig.yaml\"\nafter: fit\naxes:\n"
      << "  slide_mm: [1500, 2500]\n  theta_deg: [0, 30]\n  bias_ma: [475, 500]\n"
      << "bracket:\n  t_ref_ms: 8\n  t_meas_ms: [30, 36]\n";
  const Recipe recipe = LoadRecipe((dir / "recipe.yaml").string());
  const std::string text = SuggestProbeRecipe(recipe, PlanRecipe(recipe));
  std::ofstream(dir / "probe-recipe.yaml") << text;
  const Recipe probe = LoadRecipe((dir / "probe-recipe.yaml").string());
  EXPECT_EQ(probe.name, "bench: #2-probe") << text;
  EXPECT_TRUE(fs::equivalent(probe.rig_path, dir / "rigs/my rig.yaml")) << text;
  EXPECT_EQ(probe.sweep.bracket.t_meas_ms, std::vector<double>{36.0}) << text;
  EXPECT_EQ(PlanRecipe(probe).poses.size(), 8u) << text;
  fs::remove_all(dir.parent_path());
}

// The issue: `calibrate --out DIR` silently replaced the model.yaml, features.csv and report of
// DIR. Refused (pointing to --resume), before any device starts; nothing is touched.
TEST(RunFolderTest, CalibrateOutOntoAnotherRunsResultsIsRefused) {
  namespace fs = std::filesystem;
  const fs::path dir =
      fs::temp_directory_path() / ("irdist-run-out-" + std::to_string(::getpid()));
  for (const char* result : {"model.yaml", "features.csv", "report", "recording"}) {
    fs::remove_all(dir);
    fs::create_directories(dir);
    std::ofstream(dir / result) << "theirs\n";
    CalibrateArgs args;
    args.recipe = std::string(IRDIST_SOURCE_DIR) + "/recipes/smoke-calibration.yaml";
    args.out_dir = dir.string();
    args.quiet = true;
    std::ostringstream out, err;
    try {
      RunCalibrate(args, {out, err});
      ADD_FAILURE() << "calibrate --out onto " << result;
    } catch (const RunFolderError& e) {
      EXPECT_NE(std::string(e.what()).find((dir / result).string() + " exists already"),
                std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("--resume"), std::string::npos) << e.what();
    }
    std::ifstream in(dir / result);
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_EQ(text, "theirs\n") << result;
  }
  fs::remove_all(dir);
}

// plan --suggest --from: a summary whose best_dt_ms no exposure can hold, or a FIFO, is refused
// before the probe sweep (nothing is started, no probe folder is made); it was checked after it.
TEST(RunSuggestTest, ABadFromIsRefusedBeforeTheProbeSweep) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("irdist_suggest_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "summary.yaml") << "best_dt_ms: 1e308\n";
  ASSERT_EQ(::mkfifo((dir / "fifo.yaml").c_str(), 0600), 0);
  for (const char* from : {"summary.yaml", "fifo.yaml"}) {
    SCOPED_TRACE(from);
    PlanArgs args;
    args.recipe = std::string(IRDIST_SOURCE_DIR) + "/recipes/smoke-calibration.yaml";
    args.suggest = true;
    args.from_summary = (dir / from).string();
    args.out_dir = (dir / "probe").string();
    std::ostringstream out, err;
    try {
      RunSuggest(args, {out, err});
      ADD_FAILURE() << "accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(args.from_summary), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("(0, 100000]"), std::string::npos) << e.what();
    }
    EXPECT_FALSE(fs::exists(dir / "probe"));
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace irdist
