// What fit and playback check before they write: the default folder of their results, results
// never replaced unasked nor written through a link, and a recording a live process writes.
#include "app/runs/offline_inputs.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "acquisition/recording_writer.h"
#include "app/inputs/errors.h"
#include "tests/app/small_recording.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;
using testing::SmallRecordingTest;

// A recording's results go into its run folder: the folder that holds it, with or without a
// trailing slash; a bare name's is the current folder.
TEST(ParentOf, IsTheFolderThatHoldsThePath) {
  EXPECT_EQ(ParentOf("runs/cal/recording"), "runs/cal");
  EXPECT_EQ(ParentOf("runs/cal/recording/"), "runs/cal");
  EXPECT_EQ(ParentOf("/data/cal/model.yaml"), "/data/cal");
  EXPECT_EQ(ParentOf("recording"), ".");
}

TEST_F(SmallRecordingTest, ExistingResultsAreRefusedWithoutForceAndReplacedWithIt) {
  std::ofstream(dir_ / "features.csv") << "the live run's\n";
  try {
    RefuseExistingResults(dir_.string(), {"model.yaml", "features.csv"}, false, "fit");
    FAIL() << "an existing features.csv was not refused";
  } catch (const RunFolderError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find((dir_ / "features.csv").string() + " exists: irdist fit"),
              std::string::npos) << what;
    EXPECT_NE(what.find("--force"), std::string::npos) << what;
  }
  EXPECT_NO_THROW(RefuseExistingResults(dir_.string(), {"features.csv"}, true, "fit"));
  EXPECT_NO_THROW(RefuseExistingResults(dir_.string(), {"model.yaml", "report"}, false, "fit"));
}

// A link is never written through, even with --force (the file it points to stays as it was).
TEST_F(SmallRecordingTest, ALinkedResultIsRefusedEvenWithForce) {
  fs::create_symlink(dir_ / "elsewhere.csv", dir_ / "estimates.csv");  // dangling: still a link
  try {
    RefuseExistingResults(dir_.string(), {"estimates.csv"}, true, "playback");
    FAIL() << "a linked estimates.csv was accepted";
  } catch (const RunFolderError& e) {
    EXPECT_NE(std::string(e.what()).find("is a symbolic link: irdist playback never writes"),
              std::string::npos) << e.what();
  }
}

TEST_F(SmallRecordingTest, ARecordingIsRefusedWhileALiveWriterHoldsIt) {
  const std::string recording = (dir_ / "recording").string();
  EXPECT_NO_THROW(RefuseLiveWriter(recording, "playback"));  // the fixture's writer has closed
  auto live = RecordingWriter::Resume(recording);
  try {
    RefuseLiveWriter(recording, "playback");
    FAIL() << "a recording being written was accepted";
  } catch (const RunFolderError& e) {
    EXPECT_NE(std::string(e.what()).find("is being written by process " +
                                         std::to_string(getpid())), std::string::npos) << e.what();
  }
  live->Close(Completion::kCut);
  EXPECT_NO_THROW(RefuseLiveWriter(recording, "playback"));
}

}  // namespace
}  // namespace irdist
