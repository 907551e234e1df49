// A run folder's results (app/runs/run_results.h): a recording with errors refused before anything
// is computed, a result that cannot be written turned into a RunFolderError that says what to
// run once it is fixed, and a recording-only run's features.csv.
#include "app/runs/run_results.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "app/inputs/errors.h"
#include "app/processing/estimates_csv.h"
#include "app/reports/report.h"
#include "estimator/model_file_error.h"
#include "tests/app/small_recording.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;
using testing::ReadAll;
using testing::SmallRecordingTest;

// The message of the RunFolderError WriteResults makes of `error`, or "" when none leaves it.
template <typename E>
std::string RefusedAs(const E& error) {
  try {
    WriteResults("rerun with --force", [&error] { throw error; });
  } catch (const RunFolderError& e) {
    return e.what();
  }
  return "";
}

TEST(WriteResults, AResultThatCannotBeWrittenSaysWhatToRunOnceFixed) {
  const std::string then = "\nOnce that is fixed, rerun with --force";
  EXPECT_EQ(RefusedAs(ReportError("report/: disk full")), "report/: disk full" + then);
  EXPECT_EQ(RefusedAs(EstimatesFileError("estimates.csv: disk full")),
            "estimates.csv: disk full" + then);
  const ModelFileError model_error("model.yaml", "", 0, "read-only folder");
  EXPECT_EQ(RefusedAs(model_error), model_error.what() + then);
  EXPECT_EQ(RefusedAs(RecordingError("features.csv: no space")), "features.csv: no space" + then);
  // Anything else leaves as it was: it is not a result that could not be written.
  EXPECT_THROW(WriteResults("x", [] { throw CheckFailedError("bad recording"); }),
               CheckFailedError);
  bool ran = false;
  WriteResults("x", [&ran] { ran = true; });
  EXPECT_TRUE(ran);
}

TEST_F(SmallRecordingTest, ACleanRecordingPassesAndOneWithErrorsIsRefusedWithItsLines) {
  const std::string recording = (dir_ / "recording").string();
  EXPECT_NO_THROW(RequireCleanRecording(recording));
  const fs::path csv = dir_ / "recording" / "frames.csv";
  std::string text = ReadAll(csv.string());
  text.replace(text.find("frames/000001.png"), 17, "frames/../../x.png");
  std::ofstream(csv, std::ios::binary | std::ios::trunc) << text;
  try {
    RequireCleanRecording(recording, "it is not resumed");
    FAIL() << "a recording with errors passed";
  } catch (const CheckFailedError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(recording + ": the recording has "), std::string::npos) << what;
    EXPECT_NE(what.find("; it is not resumed. First:"), std::string::npos) << what;
    EXPECT_NE(what.find("frames.csv:3"), std::string::npos) << what;
    EXPECT_NE(what.find("irdist check " + recording), std::string::npos) << what;
  }
}

TEST_F(SmallRecordingTest, ARecordingOnlyRunWritesItsFeatures) {
  std::ostringstream out;
  ProcessRecordingOnly(dir_.string(), FeatureOptions{}, {}, out);
  EXPECT_TRUE(fs::exists(dir_ / "features.csv"));
  EXPECT_NE(out.str().find("(recipe: after: none); features: " + (dir_ / "features.csv").string()),
            std::string::npos)
      << out.str();
  EXPECT_FALSE(fs::exists(dir_ / "model.yaml"));
  EXPECT_FALSE(fs::exists(dir_ / "estimates.csv"));
}

}  // namespace
}  // namespace irdist
