// A live run's folder: its results by kind, a new folder made and locked for the whole run (a
// second run beside it refused), another run's results never replaced, earlier station logs kept,
// and the full-disk advice naming the resume.
#include "app/runs/run_folder.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "app/inputs/errors.h"
#include "app/inputs/recipe.h"
#include "station/plan.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;

class RunFolderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("irdist-run-folder-" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    recipe_ = LoadRecipe(std::string(IRDIST_SOURCE_DIR) + "/recipes/smoke-calibration.yaml");
    plan_ = PlanRecipe(recipe_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  RunFolder Open(RunKind kind, std::ostream& err) {
    return OpenRunFolder(kind, dir_.string(), "", recipe_, plan_, "", err);
  }

  fs::path dir_;
  Recipe recipe_;
  Plan plan_;
};

TEST_F(RunFolderTest, ResultsFollowTheKindAndTheRecipesAfter) {
  EXPECT_STREQ(CommandName(RunKind::kCalibrate), "calibrate");
  EXPECT_STREQ(CommandName(RunKind::kValidate), "validate");
  Recipe recipe = recipe_;
  recipe.after = AfterRecording::kFit;
  EXPECT_EQ(ResultsOf(RunKind::kCalibrate, recipe),
            (std::vector<std::string>{"model.yaml", "report/index.html"}));
  recipe.after = AfterRecording::kEstimate;
  EXPECT_EQ(ResultsOf(RunKind::kValidate, recipe),
            (std::vector<std::string>{"estimates.csv", "summary.yaml", "report/index.html"}));
  recipe.after = AfterRecording::kNone;
  EXPECT_EQ(ResultsOf(RunKind::kValidate, recipe), std::vector<std::string>{"features.csv"});
}

// A new --out folder is made and held: a second run into it is refused naming this process, and
// it is free again once the first run's folder is released.
TEST_F(RunFolderTest, ANewFolderIsMadeAndLockedForTheWholeRun) {
  std::ostringstream err;
  {
    const RunFolder folder = Open(RunKind::kCalibrate, err);
    EXPECT_EQ(folder.dir, dir_.string());
    EXPECT_TRUE(folder.record);
    EXPECT_TRUE(folder.done_ids.empty());
    ASSERT_NE(folder.lock, nullptr);
    EXPECT_TRUE(fs::is_directory(dir_));
    try {
      Open(RunKind::kValidate, err);
      ADD_FAILURE() << "a second run into a locked folder";
    } catch (const RunFolderError& e) {
      EXPECT_NE(std::string(e.what()).find("in use by a live run (irdist calibrate, process " +
                                           std::to_string(::getpid())),
                std::string::npos)
          << e.what();
    }
  }
  EXPECT_NO_THROW(Open(RunKind::kValidate, err));
  EXPECT_EQ(err.str(), "");
}

// Another run's recording or results, or a link in their place, are never replaced.
TEST_F(RunFolderTest, AnotherRunsResultsOrALinkInTheirPlaceAreRefused) {
  fs::create_directories(dir_);
  fs::create_symlink("/nonexistent", dir_ / "summary.yaml");
  try {
    RefuseOtherResults(dir_.string(), RunKind::kValidate);
    ADD_FAILURE() << "a link named summary.yaml was accepted";
  } catch (const RunFolderError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find((dir_ / "summary.yaml").string() + " exists already: irdist validate"),
              std::string::npos) << what;
    EXPECT_NE(what.find("--resume"), std::string::npos) << what;
  }
  EXPECT_FALSE(fs::exists(dir_ / "run.lock"));
}

TEST_F(RunFolderTest, EarlierStationLogsAreKeptUnderFreeNames) {
  fs::create_directories(dir_);
  EXPECT_EQ(KeepEarlierLog(dir_.string()), "");
  std::ofstream(dir_ / "station.log") << "first\n";
  EXPECT_EQ(KeepEarlierLog(dir_.string()), (dir_ / "station.1.log").string());
  std::ofstream(dir_ / "station.log") << "second\n";
  EXPECT_EQ(KeepEarlierLog(dir_.string()), (dir_ / "station.2.log").string());
  EXPECT_FALSE(fs::exists(dir_ / "station.log"));
  std::ifstream first(dir_ / "station.1.log");
  std::string line;
  std::getline(first, line);
  EXPECT_EQ(line, "first");
}

TEST_F(RunFolderTest, TheFullDiskAdviceNamesTheResume) {
  EXPECT_EQ(CompleteResultsAdvice(RunKind::kValidate, "r.yaml", "m.yaml", "runs/a b"),
            "complete the results with: irdist validate r.yaml --model m.yaml --resume 'runs/a b'");
}

}  // namespace
}  // namespace irdist
