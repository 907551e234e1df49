// `irdist check` on a small hand-made recording and on estimates.csv files: what it counts, and
// that a recording with errors or an unreadable estimates.csv fails the check.
#include "app/runs/check_command.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "app/inputs/errors.h"
#include "app/processing/estimates_csv.h"
#include "tests/app/small_recording.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;
using testing::ReadAll;
using testing::SmallRecordingTest;

// The fixture's recording: 5 frames, bracket 0 complete (4 frames), bracket 1 cut after its
// reference; nothing wrong with it.
TEST_F(SmallRecordingTest, CheckCountsTheFramesAndCompleteBracketsOfACleanRecording) {
  std::ostringstream out, err;
  CheckArgs args;
  args.recording = (dir_ / "recording").string();
  RunCheck(args, {out, err});
  const std::string text = out.str();
  EXPECT_NE(text.find("recording cut, 5 frames, 1/2 brackets complete, 0 errors"),
            std::string::npos) << text;
}

// A row naming a frame outside the recording is an error: listed by file and line, and the
// check fails with the count the report gave.
TEST_F(SmallRecordingTest, CheckFailsOnARecordingWithErrors) {
  const fs::path csv = dir_ / "recording" / "frames.csv";
  std::string text = ReadAll(csv.string());
  text.replace(text.find("frames/000001.png"), 17, "frames/../../x.png");
  std::ofstream(csv, std::ios::binary | std::ios::trunc) << text;
  std::ostringstream out, err;
  CheckArgs args;
  args.recording = (dir_ / "recording").string();
  try {
    RunCheck(args, {out, err});
    FAIL() << "a recording with errors passed the check:\n" << out.str();
  } catch (const CheckFailedError& e) {
    std::smatch count;
    const std::string report = out.str();
    ASSERT_TRUE(std::regex_search(report, count, std::regex(", ([0-9]+) errors,"))) << report;
    EXPECT_GE(std::stoi(count[1]), 1) << report;
    EXPECT_NE(std::string(e.what()).find(": " + count[1].str() + " error(s) in the recording"),
              std::string::npos) << e.what();
  }
  EXPECT_NE(out.str().find("frames.csv:3"), std::string::npos) << out.str();
}

// An estimates.csv: its rows and brackets counted (brackets 3, 4 and 7: 3 brackets, 3 to 7),
// a torn last line (the writer killed mid-row) dropped with a note.
TEST_F(SmallRecordingTest, CheckCountsTheRowsAndBracketsOfAnEstimatesFile) {
  std::vector<EstimateRow> rows(4);
  rows[0].bracket = 3;
  rows[1].bracket = 4;
  rows[2].bracket = 4;
  rows[3].bracket = 7;
  for (EstimateRow& row : rows) {
    row.method = "i0_free";
    row.true_d_mm = 2000.0;
    row.d_mm = 2010.0;
  }
  const std::string path = (dir_ / "estimates.csv").string();
  WriteEstimatesCsv(path, rows);
  std::ostringstream out, err;
  CheckArgs args;
  args.recording = path;
  RunCheck(args, {out, err});
  EXPECT_EQ(out.str(), path + ": 4 estimate rows of 3 brackets (3 to 7), readable\n");
  std::ofstream(path, std::ios::app) << "8,0,0,i0_";
  std::ostringstream torn;
  RunCheck(args, {torn, err});
  EXPECT_NE(torn.str().find("4 estimate rows of 3 brackets (3 to 7), readable\nnote: "),
            std::string::npos) << torn.str();
}

TEST_F(SmallRecordingTest, CheckFailsOnAFileThatIsNoEstimatesCsv) {
  const std::string path = (dir_ / "notes.txt").string();
  std::ofstream(path) << "not an estimates file\n1,2,3\n";
  std::ostringstream out, err;
  CheckArgs args;
  args.recording = path;
  EXPECT_THROW(RunCheck(args, {out, err}), CheckFailedError);
}

}  // namespace
}  // namespace irdist
