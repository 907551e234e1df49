// The recording's writer: staged brackets committed whole, crash safety (a writer SIGKILLed mid-run
// or while staging), one writer at a time, resuming a cut run (leftovers set aside, nothing
// deleted, never through a planted link), the first write error kept, hashes and time columns.
#include "acquisition/recording_writer.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <regex>
#include <sstream>
#include <thread>

#include "acquisition/content_hash.h"
#include "acquisition/recording_check.h"
#include "acquisition/recording_reader.h"
#include "tests/acquisition/recording_helpers.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;

TEST(Recording, StagedBracketIsInvisibleUntilCommittedThenWhole) {
  const std::string dir = TempDir("staged");
  auto writer = RecordingWriter::Open(dir, TestHeader());
  WriteFrames(*writer, 0, kBracketSize);
  std::vector<FrameRecord> records;
  for (std::int64_t i = kBracketSize; i < 2 * kBracketSize; ++i) {
    EXPECT_EQ(writer->Stage(TestImage(i)), i);
    records.push_back(TestRecord(i));
  }
  EXPECT_EQ(writer->staged_count(), static_cast<std::size_t>(kBracketSize));
  EXPECT_EQ(CountCsvRows(dir), kBracketSize);
  EXPECT_EQ(RecordingReader(dir).rows().size(), static_cast<std::size_t>(kBracketSize));
  EXPECT_EQ(FramesDirNames(dir).back(), "000009.png.tmp");
  EXPECT_FALSE(fs::exists(fs::path(dir) / "frames/000005.png"));
  EXPECT_THROW(writer->CommitStaged({TestRecord(5)}), CheckError);  // one record per frame
  EXPECT_THROW(writer->Append(TestImage(5), TestRecord(5)), CheckError);

  const std::vector<FrameRecord> committed = writer->CommitStaged(records);
  ASSERT_EQ(committed.size(), static_cast<std::size_t>(kBracketSize));
  EXPECT_EQ(committed.back().file, "frames/000009.png");
  EXPECT_EQ(writer->next_index(), 2 * kBracketSize);
  writer->Close(Completion::kComplete);
  RecordingReader reader(dir);
  ASSERT_EQ(reader.rows().size(), static_cast<std::size_t>(2 * kBracketSize));
  for (const FrameRecord& row : reader.rows()) {
    EXPECT_EQ(cv::norm(reader.LoadImage(row), TestImage(row.index), cv::NORM_INF), 0.0);
  }
  const RecordingCheck check = CheckRecording(dir);
  EXPECT_TRUE(check.ok() && check.warnings.empty()) << check.BriefReport();
  fs::remove_all(dir);
}

TEST(Recording, DroppedStagedFramesLeaveNoFileAndTheirIndicesAreReused) {
  const std::string dir = TempDir("dropstaged");
  auto writer = RecordingWriter::Open(dir, TestHeader());
  for (int i = 0; i < 3; ++i) writer->Stage(TestImage(100 + i));
  writer->DropStaged();
  EXPECT_TRUE(FramesDirNames(dir).empty());
  WriteFrames(*writer, 0, 2);
  writer->Close(Completion::kComplete);
  RecordingReader reader(dir);
  ASSERT_EQ(reader.rows().size(), 2u);
  EXPECT_EQ(reader.rows()[1].file, "frames/000001.png");
  EXPECT_EQ(cv::norm(reader.LoadImage(reader.rows()[1]), TestImage(1), cv::NORM_INF), 0.0);
  fs::remove_all(dir);
}

TEST(RecordingSafety, KilledWhileStagingLosesOnlyTheStagedBracketAndResumeSetsItAside) {
  const std::string dir = TempDir("killstaged");
  auto writer = RecordingWriter::Open(dir, TestHeader());
  WriteFrames(*writer, 0, kBracketSize);
  for (std::int64_t i = kBracketSize; i < kBracketSize + 3; ++i) writer->Stage(TestImage(i));
  writer.reset();  // no Close, no commit: as after a kill
  EXPECT_EQ(CountCsvRows(dir), kBracketSize);
  auto resumed = RecordingWriter::Resume(dir);
  EXPECT_EQ(resumed->next_index(), kBracketSize);
  ASSERT_EQ(resumed->set_aside().size(), 3u);
  EXPECT_EQ(resumed->set_aside().front(), "frames/000005.png.tmp");
  resumed->Close(Completion::kComplete);
  const RecordingCheck check = CheckRecording(dir);
  EXPECT_TRUE(check.ok()) << check.BriefReport();
  EXPECT_EQ(check.complete_brackets, 1);
  fs::remove_all(dir);
}

TEST(Recording, WriterRefusesARowTheReaderWouldRefuseAndWritesNothing) {
  const std::string dir = TempDir("unreadable");
  auto writer = RecordingWriter::Open(dir, TestHeader());
  WriteFrames(*writer, 0, 1);
  FrameRecord bad = TestRecord(1);
  bad.bracket_size = 0;  // no bracket has zero frames
  EXPECT_THROW(writer->Append(TestImage(1), bad), CheckError);
  EXPECT_EQ(CountCsvRows(dir), 1);
  EXPECT_FALSE(fs::exists(fs::path(dir) / "frames" / "000001.png"));
  WriteFrames(*writer, 1, 2);  // the writer goes on with the next good frame
  writer->Close(Completion::kCut);
  EXPECT_EQ(RecordingReader(dir).rows().size(), 2u);
}

// Forks a process that opens a recording at `dir` and appends frames to it until it is killed (or
// a write fails: then it exits with 3). Returns the child's pid, -1 if the fork failed.
pid_t ForkEndlessWriter(const std::string& dir) {
  const pid_t child = ::fork();
  if (child == 0) {
    try {
      auto writer = RecordingWriter::Open(dir, TestHeader());
      for (std::int64_t i = 0;; ++i) writer->Append(TestImage(i), TestRecord(i));
    } catch (...) {
    }
    ::_exit(3);
  }
  return child;
}

// Waits until the recording at `dir` has `rows` rows in its CSV, or `timeout` has passed.
void WaitForCsvRows(const std::string& dir, int rows, std::chrono::seconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (CountCsvRows(dir) < rows && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}

TEST(Recording, WriterKilledMidRunLosesAtMostTheFrameInFlight) {
  const std::string dir = TempDir("killed");
  const pid_t child = ForkEndlessWriter(dir);
  ASSERT_GE(child, 0);
  // Kill it once it has written a few brackets, in the middle of its work.
  WaitForCsvRows(dir, 23, std::chrono::seconds(20));
  ::kill(child, SIGKILL);
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFSIGNALED(status)) << "the writer ended by itself";

  RecordingReader reader(dir);
  EXPECT_EQ(reader.completion(), Completion::kRunning);
  EXPECT_FALSE(reader.IsComplete());
  const auto& rows = reader.rows();
  ASSERT_GE(rows.size(), 23u);
  for (size_t i = 0; i < rows.size(); ++i) {
    EXPECT_EQ(rows[i].index, static_cast<std::int64_t>(i));  // every frame once, in order
    const cv::Mat image = reader.LoadImage(rows[i]);
    EXPECT_EQ(cv::norm(image, TestImage(rows[i].index), cv::NORM_INF), 0.0) << rows[i].file;
  }
  const std::int64_t written = static_cast<std::int64_t>(rows.size());
  std::set<std::int64_t> expected_complete;
  for (std::int64_t id = 0; id < written / kBracketSize; ++id) expected_complete.insert(id);
  EXPECT_EQ(reader.CompleteBracketIds(), expected_complete);

  const RecordingCheck check = CheckRecording(dir);
  EXPECT_TRUE(check.ok()) << check.BriefReport();
  EXPECT_EQ(check.completion, Completion::kRunning);
  EXPECT_NE(check.BriefReport().find("treat as cut"), std::string::npos);

  // Resume: the rest of the run is appended after the last index and the run completes.
  const std::int64_t total = (written / kBracketSize + 2) * kBracketSize;
  auto writer = RecordingWriter::Resume(dir);
  EXPECT_EQ(writer->next_index(), written);
  const std::int64_t first_incomplete = written / kBracketSize * kBracketSize;
  for (std::int64_t i = first_incomplete; i < total; ++i) {
    writer->Append(TestImage(i), TestRecord(i));
  }
  writer->Close(Completion::kComplete);
  RecordingReader resumed(dir);
  EXPECT_TRUE(resumed.IsComplete());
  EXPECT_EQ(resumed.header().resumed.size(), 1u);
  EXPECT_EQ(static_cast<std::int64_t>(resumed.CompleteBracketIds().size()), total / kBracketSize);
  for (const auto& bracket : resumed.Brackets()) {
    ASSERT_TRUE(bracket.complete);
    for (const FrameRecord& row : bracket.frames) {
      EXPECT_EQ(row.frame_in_bracket, static_cast<int>(&row - bracket.frames.data()));
    }
  }
  const RecordingCheck after = CheckRecording(dir);
  EXPECT_TRUE(after.ok()) << after.BriefReport();
  fs::remove_all(dir);
}

TEST(RecordingSafety, SecondWriterIsRefusedNamingThePidOfTheFirst) {
  const std::string dir = TempDir("twowriters");
  auto first = RecordingWriter::Open(dir, TestHeader());
  WriteFrames(*first, 0, 3);
  try {
    RecordingWriter::Resume(dir);
    FAIL() << "a resume beside a live writer was accepted";
  } catch (const RecordingError& error) {
    EXPECT_NE(std::string(error.what()).find("being written by process " +
                                             std::to_string(::getpid())),
              std::string::npos)
        << error.what();
  }
  WriteFrames(*first, 3, 5);  // the first writer goes on undisturbed
  first.reset();              // its lock goes with it
  EXPECT_EQ(RecordingWriter::Resume(dir)->next_index(), 5);
  EXPECT_TRUE(CheckRecording(dir).ok()) << CheckRecording(dir).BriefReport();
  fs::remove_all(dir);
}

TEST(RecordingSafety, ResumeOfACutFramesCsvMovesLeftoversAsideAndDeletesNothing) {
  const std::string dir = TempDir("cutcsv");
  auto writer = RecordingWriter::Open(dir, TestHeader());
  WriteFrames(*writer, 0, 20);
  writer.reset();
  std::istringstream in(Slurp(fs::path(dir) / "frames.csv"));
  std::string kept, line;
  for (int n = 0; n < 11 && std::getline(in, line); ++n) kept += line + "\n";  // header + 10 rows
  WriteText(fs::path(dir) / "frames.csv", kept);
  auto resumed = RecordingWriter::Resume(dir);
  EXPECT_EQ(resumed->next_index(), 10);
  ASSERT_EQ(resumed->set_aside().size(), 10u);
  EXPECT_EQ(resumed->set_aside().front(), "frames/000010.png");
  int pngs = 0;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    if (entry.path().extension() == ".png") ++pngs;
  }
  EXPECT_EQ(pngs, 20) << "a frame was deleted";
  EXPECT_TRUE(fs::exists(fs::path(resumed->set_aside_dir()) / "000019.png"));
  fs::remove_all(dir);
}

TEST(RecordingSafety, FirstWriteErrorIsReportedAndTheRecordingClosesAsCut) {
  const std::string dir = TempDir("writefail");
  auto writer = RecordingWriter::Open(dir, TestHeader());
  WriteFrames(*writer, 0, 2);
  // A file size limit below a PNG's size: the next frame's write fails like on a full disk.
  struct rlimit saved {};
  ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &saved), 0);
  ::signal(SIGXFSZ, SIG_IGN);
  struct rlimit small = saved;
  small.rlim_cur = 64 * 1024;
  cv::Mat noise(512, 512, CV_16UC1);
  cv::randu(noise, 0, 65535);  // a PNG of ~500 KB
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &small), 0);
  std::string first_error;
  try {
    writer->Append(noise, TestRecord(2));
  } catch (const RecordingError& error) {
    first_error = error.what();
  }
  EXPECT_NO_THROW(writer->Close(Completion::kComplete));
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &saved), 0);
  EXPECT_NE(first_error.find("frames/000002.png.tmp"), std::string::npos) << first_error;
  EXPECT_TRUE(writer->failed());
  const RecordingReader reader(dir);
  EXPECT_EQ(reader.completion(), Completion::kCut) << "a failed run must not read as complete";
  EXPECT_EQ(reader.rows().size(), 2u);
  EXPECT_FALSE(fs::exists(fs::path(dir) / "frames/000002.png.tmp"));
  fs::remove_all(dir);
}

// Every row carries its PNG's SHA-256, and recording.yaml frames.csv's once closed.
TEST(RecordingIntegrity, RowsCarryTheirPngsHashAndTheHeaderFramesCsvs) {
  const std::string dir = CompleteRecording("hashes", kBracketSize);
  const RecordingReader reader(dir);
  EXPECT_EQ(reader.header().format_version, 2);
  ASSERT_EQ(reader.rows().size(), static_cast<size_t>(kBracketSize));
  for (const FrameRecord& row : reader.rows()) {
    EXPECT_EQ(row.sha256, Sha256Hex(Slurp(fs::path(dir) / row.file))) << row.file;
  }
  EXPECT_EQ(reader.header().frames_csv_sha256, Sha256Hex(Slurp(fs::path(dir) / "frames.csv")));
  EXPECT_TRUE(CheckRecording(dir).ok()) << CheckRecording(dir).BriefReport();
  fs::remove_all(dir);
}

// A resume clears the hash while the file grows, and the new close writes the new one.
TEST(RecordingIntegrity, AResumedRecordingIsHashedAgainAtItsClose) {
  const std::string dir = TempDir("resumehash");
  auto writer = RecordingWriter::Open(dir, TestHeader());
  WriteFrames(*writer, 0, kBracketSize);
  writer->Close(Completion::kCut);
  EXPECT_TRUE(CheckRecording(dir).ok()) << CheckRecording(dir).BriefReport();
  auto resumed = RecordingWriter::Resume(dir);
  EXPECT_EQ(ReadRecordingHeader(dir).frames_csv_sha256, "");
  WriteFrames(*resumed, kBracketSize, 2 * kBracketSize);
  resumed->Close(Completion::kComplete);
  EXPECT_EQ(ReadRecordingHeader(dir).frames_csv_sha256,
            Sha256Hex(Slurp(fs::path(dir) / "frames.csv")));
  EXPECT_TRUE(CheckRecording(dir).ok()) << CheckRecording(dir).BriefReport();
  fs::remove_all(dir);
}

// The issue: a resume appended to a frames.csv edited after its close and hashed the edit as its
// own; check then said 0 errors. The resume refuses, and the recording keeps its old hash.
TEST(RecordingIntegrity, ResumeRefusesAFramesCsvEditedAfterItsClose) {
  const std::string dir = TempDir("resumeedited");
  auto writer = RecordingWriter::Open(dir, TestHeader());
  WriteFrames(*writer, 0, kBracketSize);
  writer->Close(Completion::kCut);
  const std::string hash = ReadRecordingHeader(dir).frames_csv_sha256;
  EditCsvLine(dir, 3, [](std::string line) {
    return std::regex_replace(line, std::regex(",1500,10,"), ",1600,10,");
  });
  try {
    RecordingWriter::Resume(dir);
    FAIL() << "an edited frames.csv was resumed";
  } catch (const RecordingError& e) {
    EXPECT_NE(std::string(e.what()).find("frames.csv was edited after the recording was closed"),
              std::string::npos) << e.what();
  }
  EXPECT_EQ(ReadRecordingHeader(dir).frames_csv_sha256, hash);
  EXPECT_EQ(ReadRecordingHeader(dir).completion, Completion::kCut);
  EXPECT_FALSE(CheckRecording(dir).ok());
  fs::remove_all(dir);
}

// A header downgraded to format 1 (hashes dropped) is not resumed either.
TEST(RecordingIntegrity, ResumeRefusesAHeaderDowngradedToFormat1) {
  const std::string dir = TempDir("resumedowngrade");
  auto writer = RecordingWriter::Open(dir, TestHeader());
  WriteFrames(*writer, 0, kBracketSize);
  writer->Close(Completion::kCut);
  const std::string yaml = Slurp(fs::path(dir) / "recording.yaml");
  WriteText(fs::path(dir) / "recording.yaml",
            std::regex_replace(yaml, std::regex("format_version: 2"), "format_version: 1"));
  EXPECT_THROW(RecordingWriter::Resume(dir), RecordingError);
  fs::remove_all(dir);
}

// A writer that died left no hash of frames.csv: the resume cannot vouch for those rows, and
// says so in recording.yaml for good (check names them), while its own rows are hashed at close.
TEST(RecordingIntegrity, RowsOfAWriterThatDiedStayMarkedUnverifiedAfterAResume) {
  const std::string dir = TempDir("resumedied");
  auto writer = RecordingWriter::Open(dir, TestHeader());
  WriteFrames(*writer, 0, kBracketSize);
  writer.reset();  // killed: completion stays running, no hash
  auto resumed = RecordingWriter::Resume(dir);
  WriteFrames(*resumed, kBracketSize, 2 * kBracketSize);
  resumed->Close(Completion::kComplete);
  EXPECT_EQ(ReadRecordingHeader(dir).unverified_rows, kBracketSize);
  const RecordingCheck check = CheckRecording(dir);
  EXPECT_TRUE(check.ok()) << check.BriefReport();
  EXPECT_NE(check.BriefReport().find("UNVERIFIED: the first 5 rows of frames.csv (lines 2 to 6)"),
            std::string::npos) << check.BriefReport();
  fs::remove_all(dir);
}

// Stale temporary files that are links (the issue: a resume wrote the header outside the
// folder): unlinked, never followed.
TEST(RecordingSafety, ResumeNeverWritesThroughAPlantedTemporaryLink) {
  const std::string dir = TempDir("tmplink");
  auto writer = RecordingWriter::Open(dir, TestHeader());
  WriteFrames(*writer, 0, kBracketSize);
  writer->Close(Completion::kCut);
  const fs::path victim = fs::path(dir + "-victim");
  WriteText(victim, "precious");
  fs::create_symlink(victim, fs::path(dir) / "recording.yaml.tmp");
  fs::create_symlink(victim, fs::path(dir) / "frames/000005.png.tmp");
  auto resumed = RecordingWriter::Resume(dir);
  WriteFrames(*resumed, kBracketSize, 2 * kBracketSize);
  resumed->Close(Completion::kComplete);
  EXPECT_EQ(Slurp(victim), "precious");
  EXPECT_FALSE(fs::is_symlink(fs::path(dir) / "recording.yaml"));
  EXPECT_TRUE(CheckRecording(dir).ok()) << CheckRecording(dir).BriefReport();
  fs::remove_all(dir);
  fs::remove(victim);
}

TEST(RecordingSafety, LiveWriterIsNamedWithoutTakingItsLock) {
  const std::string dir = TempDir("livewriter");
  auto writer = RecordingWriter::Open(dir, TestHeader());
  EXPECT_EQ(LiveWriterOf(dir), std::to_string(::getpid()));
  EXPECT_EQ(LiveWriterOf(dir), std::to_string(::getpid()));  // still held by the writer
  writer->Close(Completion::kComplete);
  EXPECT_EQ(LiveWriterOf(dir), "");
  fs::remove_all(dir);
}

TEST(RecordingTime, EachRowCarriesItsUtcTimeMonotonicTimeAndCameraTimestampWhenGiven) {
  const std::string dir = CompleteRecording("time", kBracketSize);
  const std::vector<std::string> header = CsvFields(dir, 1);
  ASSERT_EQ(header.size(), 23u);
  EXPECT_EQ(header[20], "utc_time");
  EXPECT_EQ(header[21], "host_monotonic_ns");
  EXPECT_EQ(header[22], "sha256");
  // 1700000000 s after the epoch is 2023-11-14T22:13:20Z (date -u -d @1700000000).
  EXPECT_EQ(CsvFields(dir, 3)[20], "2023-11-14T22:13:20.000001Z");
  EXPECT_EQ(CsvFields(dir, 3)[21], "5000001000");
  EXPECT_EQ(CsvFields(dir, 3)[17], "2000000000");
  EXPECT_EQ(CsvFields(dir, 6)[17], "") << "the camera gave no timestamp: empty, not 0";
  const RecordingReader reader(dir);
  EXPECT_EQ(reader.rows()[4].camera_timestamp_ns, 0u);
  EXPECT_EQ(reader.rows()[1].camera_timestamp_ns, 2000000000u);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace irdist
