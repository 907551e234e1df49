// `irdist fit` on a small hand-made recording: results never replaced without --force nor written
// through a link, and a recording with errors, swapped frames or a live writer refused.
#include "app/runs/fit_command.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "acquisition/recording_writer.h"
#include "app/inputs/errors.h"
#include "app/runs/resume.h"
#include "tests/app/small_recording.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;
using testing::ReadAll;
using testing::SmallRecordingTest;

TEST_F(SmallRecordingTest, FitRefusesARecordingWithErrors) {
  const fs::path csv = dir_ / "recording" / "frames.csv";
  std::string text = ReadAll(csv.string());
  const size_t at = text.find("frames/000001.png");
  text.replace(at, 17, "frames/../../x.png");
  std::ofstream(csv, std::ios::binary | std::ios::trunc) << text;
  std::ostringstream out, err;
  FitArgs fit;
  fit.recording = (dir_ / "recording").string();
  fit.out = (dir_ / "fit" / "model.yaml").string();
  try {
    RunFit(fit, {out, err});
    FAIL() << "fit of a recording with errors";
  } catch (const CheckFailedError& e) {
    EXPECT_NE(std::string(e.what()).find("frames.csv:3"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir_ / "fit" / "model.yaml"));
}

// The issue: fit on a recording a live calibrate was writing only warned, and wrote into the
// live folder. Now it refuses while the writer (or the run) holds its lock, and writes nothing.
TEST_F(SmallRecordingTest, FitRefusesARecordingALiveRunIsWriting) {
  std::ostringstream out, err;
  FitArgs fit;
  fit.recording = (dir_ / "recording").string();
  {
    auto live = RecordingWriter::Resume(fit.recording);
    try {
      RunFit(fit, {out, err});
      FAIL() << "fit beside a live writer";
    } catch (const RunFolderError& e) {
      EXPECT_NE(std::string(e.what()).find("process " + std::to_string(getpid())),
                std::string::npos) << e.what();
    }
    live->Close(Completion::kCut);
  }
  {
    const RunFolderLock live(dir_.string(), "calibrate");  // recording done, processing
    EXPECT_THROW(RunFit(fit, {out, err}), RunFolderError);
  }
  EXPECT_FALSE(fs::exists(dir_ / "model.yaml"));
  EXPECT_FALSE(fs::exists(dir_ / "features.csv"));
}

// The issue: `fit --out` naming a file's folder said "filesystem error".
TEST_F(SmallRecordingTest, FitIntoAFolderThatIsAFileIsRefusedNamingIt) {
  std::ostringstream out, err;
  std::ofstream(dir_ / "plain") << "a file\n";
  FitArgs fit;
  fit.recording = (dir_ / "recording").string();
  fit.out = (dir_ / "plain" / "model.yaml").string();
  try {
    RunFit(fit, {out, err});
    FAIL() << "fit into a file";
  } catch (const RunFolderError& e) {
    EXPECT_NE(std::string(e.what()).find("exists and is not a folder"), std::string::npos)
        << e.what();
  }
}

// A result that is a link is never written through, --force or not.
TEST_F(SmallRecordingTest, FitNeverWritesThroughALinkedResult) {
  const fs::path victim = dir_.string() + "-victim";
  std::ofstream(victim) << "precious\n";
  fs::create_symlink(victim, dir_ / "features.csv");
  std::ostringstream out, err;
  FitArgs fit;
  fit.recording = (dir_ / "recording").string();
  fit.force = true;
  try {
    RunFit(fit, {out, err});
    FAIL() << "fit wrote through a linked features.csv";
  } catch (const RunFolderError& e) {
    EXPECT_NE(std::string(e.what()).find((dir_ / "features.csv").string() + " is a symbolic link"),
              std::string::npos) << e.what();
  }
  EXPECT_EQ(ReadAll(victim.string()), "precious\n");
  fs::remove(victim);
}

// Two frames swapped (the issue: fit then exited 0 with 10-18% model errors): refused, naming
// the frame.
TEST_F(SmallRecordingTest, FitRefusesSwappedFrames) {
  const fs::path a = dir_ / "recording/frames/000000.png";
  const fs::path b = dir_ / "recording/frames/000001.png";
  const fs::path tmp = dir_ / "swap.png";
  fs::rename(a, tmp);
  fs::rename(b, a);
  fs::rename(tmp, b);
  std::ostringstream out, err;
  FitArgs fit;
  fit.recording = (dir_ / "recording").string();
  fit.out = (dir_ / "fit" / "model.yaml").string();
  try {
    RunFit(fit, {out, err});
    FAIL() << "fit of swapped frames";
  } catch (const CheckFailedError& e) {
    EXPECT_NE(std::string(e.what()).find("frames/000000.png: its content is not the frame"),
              std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir_ / "fit" / "model.yaml"));
}

}  // namespace
}  // namespace irdist
