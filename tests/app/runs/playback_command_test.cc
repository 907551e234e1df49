// `irdist playback` on a small hand-made recording: results never replaced without --force nor
// written through a link, the advice after a full disk a command that works, and a recording with
// errors, swapped frames or a live writer refused.
#include "app/runs/playback_command.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "acquisition/recording_writer.h"
#include "app/inputs/errors.h"
#include "tests/full_disk.h"
#include "tests/app/small_recording.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;
using testing::ReadAll;
using testing::SmallRecordingTest;

TEST_F(SmallRecordingTest, PlaybackNeverReplacesResultsWithoutForce) {
  const std::string recording = (dir_ / "recording").string();
  std::ostringstream out, err;
  PlaybackArgs args;
  args.recording = recording;
  RunPlayback(args, {out, err});  // the first playback writes features.csv beside the recording
  const std::string first = ReadAll((dir_ / "features.csv").string());
  std::ofstream(dir_ / "features.csv", std::ios::app) << "# the live run's\n";
  EXPECT_THROW(RunPlayback(args, {out, err}), RunFolderError);
  EXPECT_EQ(ReadAll((dir_ / "features.csv").string()), first + "# the live run's\n");
  args.force = true;
  RunPlayback(args, {out, err});
  EXPECT_EQ(ReadAll((dir_ / "features.csv").string()), first);
}

TEST_F(SmallRecordingTest, PlaybackRefusesARecordingWithErrors) {
  const fs::path csv = dir_ / "recording" / "frames.csv";
  std::string text = ReadAll(csv.string());
  const size_t at = text.find("frames/000001.png");
  text.replace(at, 17, "frames/../../x.png");
  std::ofstream(csv, std::ios::binary | std::ios::trunc) << text;
  std::ostringstream out, err;
  PlaybackArgs playback;
  playback.recording = (dir_ / "recording").string();
  playback.out_dir = (dir_ / "pb").string();
  try {
    RunPlayback(playback, {out, err});
    FAIL() << "playback of a recording with errors";
  } catch (const CheckFailedError& e) {
    EXPECT_NE(std::string(e.what()).find("frames.csv:3"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir_ / "pb" / "features.csv"));
}

// The item 4 for playback: a recording a live process is writing is named as such.
TEST_F(SmallRecordingTest, PlaybackRefusesARecordingALiveRunIsWriting) {
  std::ostringstream out, err;
  PlaybackArgs args;
  args.recording = (dir_ / "recording").string();
  auto live = RecordingWriter::Resume(args.recording);
  try {
    RunPlayback(args, {out, err});
    FAIL() << "playback beside a live writer";
  } catch (const RunFolderError& e) {
    EXPECT_NE(std::string(e.what()).find("is being written by process " +
                                         std::to_string(getpid())), std::string::npos) << e.what();
  }
  live->Close(Completion::kCut);
  EXPECT_FALSE(fs::exists(dir_ / "features.csv"));
}

// The issue: a result cut by a full disk said "run again", which was then refused without
// --force. The advice is now the command that completes the results, and it does.
TEST_F(SmallRecordingTest, AResultCutByAFullDiskAdvisesACommandThatWorks) {
  std::ostringstream out, err;
  PlaybackArgs args;
  args.recording = (dir_ / "recording").string();
  args.out_dir = (dir_ / "pb dir").string();
  std::string error;
  try {
    const testing::FullDisk full;
    RunPlayback(args, {out, err});
  } catch (const RunFolderError& e) {
    error = e.what();
  }
  const std::string advice = "complete the results with: irdist playback " + args.recording +
                             " --out '" + args.out_dir + "' --force";
  ASSERT_NE(error.find(advice), std::string::npos) << error;
  EXPECT_EQ(error.find("run the command again"), std::string::npos) << error;
  args.force = true;  // what the advice says
  EXPECT_NO_THROW(RunPlayback(args, {out, err}));
  EXPECT_TRUE(fs::exists(fs::path(args.out_dir) / "features.csv"));
}

// A result that is a link is never written through, --force or not.
TEST_F(SmallRecordingTest, PlaybackNeverWritesThroughALinkedResult) {
  const fs::path victim = dir_.string() + "-victim";
  std::ofstream(victim) << "precious\n";
  fs::create_symlink(victim, dir_ / "features.csv");
  std::ostringstream out, err;
  PlaybackArgs playback;
  playback.recording = (dir_ / "recording").string();
  playback.force = true;
  try {
    RunPlayback(playback, {out, err});
    FAIL() << "playback wrote through a linked features.csv";
  } catch (const RunFolderError& e) {
    EXPECT_NE(std::string(e.what()).find((dir_ / "features.csv").string() + " is a symbolic link"),
              std::string::npos) << e.what();
  }
  EXPECT_EQ(ReadAll(victim.string()), "precious\n");
  fs::remove(victim);
}

// Two frames swapped (the issue: fit then exited 0 with 10-18% model errors): playback refuses
// them too.
TEST_F(SmallRecordingTest, PlaybackRefusesSwappedFrames) {
  const fs::path a = dir_ / "recording/frames/000000.png";
  const fs::path b = dir_ / "recording/frames/000001.png";
  const fs::path tmp = dir_ / "swap.png";
  fs::rename(a, tmp);
  fs::rename(b, a);
  fs::rename(tmp, b);
  std::ostringstream out, err;
  PlaybackArgs playback;
  playback.recording = (dir_ / "recording").string();
  playback.out_dir = (dir_ / "pb").string();
  try {
    RunPlayback(playback, {out, err});
    FAIL() << "playback of swapped frames";
  } catch (const CheckFailedError& e) {
    EXPECT_NE(std::string(e.what()).find("frames/000000.png: its content is not the frame"),
              std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace irdist
