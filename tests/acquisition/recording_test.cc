// Tests of the recording format: round trip, crash safety (a writer SIGKILLed mid-run), the checker
// on corrupted files, and resuming a cut run.
#include "acquisition/recording.h"

#include "acquisition/content_hash.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <future>
#include <regex>
#include <sstream>
#include <thread>

namespace irdist {
namespace {

namespace fs = std::filesystem;

constexpr int kBracketSize = 5;

std::string TempDir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() /
                       ("irdist_rec_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  return dir.string();
}

RecordingHeader TestHeader() {
  RecordingHeader header;
  header.software_version = "irdist test";
  header.bit_depth = 12;
  header.pixel_format = "Mono12";
  header.camera = {"Aravis", "Fake", "GV01", "0.8.26", "127.0.0.1"};
  header.camera_features = {{"PixelFormat", "Mono12"}, {"TriggerSource", "Line1"},
                            {"Width", "64"}, {"DeviceVersion", "0.8: odd # text"}};
  header.station_identity = "IRDIST-STATION 1.0";
  header.recipe_path = "recipes/table3-calibration.yaml";
  header.recipe_text = "name: table3\nexposures_us: [8000, 30000]\n# a comment: kept\n";
  header.rig_path = "recipes/rigs/virtual.yaml";
  header.rig_text = "name: virtual\nkind: virtual\n";
  return header;
}

// Frame `index` of the test run: every pixel tells its index, so a mix-up is visible.
cv::Mat TestImage(std::int64_t index) {
  cv::Mat image(24, 32, CV_16UC1, cv::Scalar(static_cast<double>(index % 4096)));
  image.at<std::uint16_t>(0, 0) = 4095;
  return image;
}

FrameRecord TestRecord(std::int64_t index) {
  FrameRecord r;
  r.bracket_id = index / kBracketSize;
  r.frame_in_bracket = static_cast<int>(index % kBracketSize);
  r.bracket_size = kBracketSize;
  r.role = r.frame_in_bracket == 0 ? FrameRole::kReference : FrameRole::kMeasurement;
  r.requested_exposure_us = 8000.0 + 2000.0 * r.frame_in_bracket;
  r.actual_exposure_us = r.requested_exposure_us + 0.25;
  r.bias_ma_set = 500.0;
  r.bias_ma_measured = r.frame_in_bracket == 2 ? std::nan("") : 499.75;
  r.slide_mm = 1500.0 + 100.0 * static_cast<double>(r.bracket_id);
  r.pan_deg = 10.0;
  r.tilt_deg = -5.5;
  r.theta_deg = 11.4;
  r.repeat = 1;
  r.camera_frame_id = static_cast<std::uint64_t>(65530 + index) % 65536;
  // Frame 4 of each bracket: a camera that gives no timestamp.
  r.camera_timestamp_ns =
      index % kBracketSize == 4 ? 0 : 1000000000ull * static_cast<std::uint64_t>(index + 1);
  r.host_time_ns = 1700000000000000000ll + 1000 * index;
  r.host_monotonic_ns = 5000000000ll + 1000 * index;
  r.status = index % 7 == 3 ? "retried" : "ok";
  return r;
}

void WriteFrames(RecordingWriter& writer, std::int64_t from, std::int64_t to) {
  for (std::int64_t i = from; i < to; ++i) writer.Append(TestImage(i), TestRecord(i));
}

int CountCsvRows(const std::string& dir) {
  std::ifstream in(fs::path(dir) / "frames.csv");
  int lines = 0;
  std::string line;
  while (std::getline(in, line)) ++lines;
  return lines - 1;
}

TEST(Recording, RoundTripGivesBackBracketsAndTheHeaderVerbatim) {
  const std::string dir = TempDir("roundtrip");
  auto writer = RecordingWriter::Open(dir, TestHeader());
  WriteFrames(*writer, 0, 3 * kBracketSize);
  writer->Close(Completion::kComplete);

  RecordingReader reader(dir);
  EXPECT_TRUE(reader.IsComplete());
  const RecordingHeader& h = reader.header();
  EXPECT_EQ(h.recipe_text, TestHeader().recipe_text);
  EXPECT_EQ(h.rig_text, TestHeader().rig_text);
  EXPECT_EQ(h.camera_features, TestHeader().camera_features);
  EXPECT_EQ(h.camera.serial, "GV01");
  EXPECT_EQ(h.bit_depth, 12);
  EXPECT_EQ(h.frame_count, 15);
  EXPECT_FALSE(h.start_time.empty());
  EXPECT_FALSE(h.end_time.empty());
  ASSERT_EQ(reader.rows().size(), 15u);
  const auto brackets = reader.Brackets();
  ASSERT_EQ(brackets.size(), 3u);
  for (const auto& bracket : brackets) {
    EXPECT_TRUE(bracket.complete);
    ASSERT_NE(bracket.Reference(), nullptr);
    EXPECT_EQ(bracket.Measurements().size(), 4u);
    for (const FrameRecord& row : bracket.frames) {
      const FrameRecord expected = TestRecord(row.index);
      EXPECT_EQ(row.bracket_id, bracket.bracket_id);
      EXPECT_DOUBLE_EQ(row.actual_exposure_us, expected.actual_exposure_us);
      EXPECT_DOUBLE_EQ(row.slide_mm, expected.slide_mm);
      EXPECT_DOUBLE_EQ(row.tilt_deg, expected.tilt_deg);
      EXPECT_EQ(std::isnan(row.bias_ma_measured), std::isnan(expected.bias_ma_measured));
      EXPECT_EQ(row.camera_frame_id, expected.camera_frame_id);
      EXPECT_EQ(row.camera_timestamp_ns, expected.camera_timestamp_ns);
      EXPECT_EQ(row.host_time_ns, expected.host_time_ns);
      EXPECT_EQ(row.host_monotonic_ns, expected.host_monotonic_ns);
      EXPECT_EQ(row.status, expected.status);
      const cv::Mat image = reader.LoadImage(row);
      EXPECT_EQ(cv::norm(image, TestImage(row.index), cv::NORM_INF), 0.0);
    }
  }
  const RecordingCheck check = CheckRecording(dir);
  EXPECT_TRUE(check.ok()) << check.BriefReport();
  EXPECT_TRUE(check.warnings.empty()) << check.BriefReport();
  EXPECT_EQ(check.complete_brackets, 3);
  EXPECT_THROW(RecordingWriter::Open(dir, TestHeader()), RecordingError);  // not empty
  EXPECT_THROW(RecordingWriter::Resume(dir), RecordingError);             // complete
  fs::remove_all(dir);
}

// The PNG and temporary files in frames/.
std::vector<std::string> FramesDirNames(const std::string& dir) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(fs::path(dir) / "frames")) {
    names.push_back(entry.path().filename().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

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

TEST(Recording, WriterKilledMidRunLosesAtMostTheFrameInFlight) {
  const std::string dir = TempDir("killed");
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    try {
      auto writer = RecordingWriter::Open(dir, TestHeader());
      for (std::int64_t i = 0;; ++i) writer->Append(TestImage(i), TestRecord(i));
    } catch (...) {
    }
    ::_exit(3);
  }
  // Kill it once it has written a few brackets, in the middle of its work.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (CountCsvRows(dir) < 23 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
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

TEST(Recording, CheckReportsCorruptPngBadRowGapAndOrphanByFileAndLine) {
  const std::string dir = TempDir("corrupt");
  auto writer = RecordingWriter::Open(dir, TestHeader());
  WriteFrames(*writer, 0, 10);
  writer->Close(Completion::kComplete);

  // Corrupt frame 4's PNG, garble the row of frame 2 (line 4), delete the row of frame 7 (line 9).
  { std::ofstream(fs::path(dir) / "frames/000004.png", std::ios::trunc) << "not a png"; }
  std::vector<std::string> lines;
  {
    std::ifstream in(fs::path(dir) / "frames.csv");
    std::string line;
    while (std::getline(in, line)) lines.push_back(line);
  }
  lines[3] = "2,frames/000002.png,0,2,5,meas,12000,twelve,readback,500,,1500,10,-5.5,11.4,1,"
             "65532,3000000000,1700000000000002000,ok,2023-11-14T22:13:20.000002Z,5000002000," +
             std::string(64, 'a');
  lines.erase(lines.begin() + 8);
  {
    std::ofstream out(fs::path(dir) / "frames.csv", std::ios::trunc);
    for (const auto& line : lines) out << line << "\n";
  }
  const RecordingCheck check = CheckRecording(dir);
  EXPECT_FALSE(check.ok());
  const std::string report = check.BriefReport();
  EXPECT_NE(report.find("frames.csv:4: bad row: bad actual_exposure_us 'twelve'"),
            std::string::npos) << report;
  EXPECT_NE(report.find("frames/000004.png: not a PNG file (no PNG signature and IHDR header) (row at frames.csv:6)"),
            std::string::npos) << report;
  EXPECT_NE(report.find("frames.csv:9: gap: indices 7..7 are missing"), std::string::npos)
      << report;
  EXPECT_NE(report.find("frames/000007.png: orphan file"), std::string::npos) << report;
  EXPECT_NE(report.find("frame_count 10 but frames.csv has 8 rows"), std::string::npos) << report;

  // The reader refuses the damaged row with its line.
  try {
    RecordingReader reader(dir);
    FAIL() << "expected RecordingError";
  } catch (const RecordingError& error) {
    EXPECT_NE(std::string(error.what()).find("frames.csv:4"), std::string::npos) << error.what();
  }
  EXPECT_THROW(CheckRecording(TempDir("nothing-here")), RecordingError);
  fs::remove_all(dir);
}

TEST(Recording, PartialLastLineAndTempFileAreWarningsNotErrors) {
  const std::string dir = TempDir("partial");
  auto writer = RecordingWriter::Open(dir, TestHeader());
  WriteFrames(*writer, 0, 6);
  writer.reset();  // no Close(): as after a crash
  { std::ofstream(fs::path(dir) / "frames.csv", std::ios::app) << "6,frames/000006.png,1,1,5,me"; }
  { std::ofstream(fs::path(dir) / "frames/000007.png.tmp") << "half"; }
  RecordingReader reader(dir);
  EXPECT_EQ(reader.rows().size(), 6u);
  const RecordingCheck check = CheckRecording(dir);
  EXPECT_TRUE(check.ok()) << check.BriefReport();
  const std::string report = check.BriefReport();
  EXPECT_NE(report.find("frames.csv:8: last line has no end of line"), std::string::npos)
      << report;
  EXPECT_NE(report.find("frames/000007.png.tmp"), std::string::npos) << report;
  EXPECT_NE(report.find("bracket 1 is incomplete (1 of 5 frames)"), std::string::npos) << report;
  fs::remove_all(dir);
}


std::string Slurp(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

void WriteText(const fs::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << text;
}

// Rewrites line `line` (1-based) of frames.csv through `edit`.
void EditCsvLine(const std::string& dir, int line, const std::function<std::string(std::string)>& edit) {
  std::istringstream in(Slurp(fs::path(dir) / "frames.csv"));
  std::string out, text;
  for (int n = 1; std::getline(in, text); ++n) out += (n == line ? edit(text) : text) + "\n";
  WriteText(fs::path(dir) / "frames.csv", out);
}

std::string CompleteRecording(const std::string& name, int frames) {
  const std::string dir = TempDir(name);
  auto writer = RecordingWriter::Open(dir, TestHeader());
  WriteFrames(*writer, 0, frames);
  writer->Close(Completion::kComplete);
  return dir;
}

std::string ReaderError(const std::string& dir) {
  try {
    const RecordingReader reader(dir);
    for (const FrameRecord& row : reader.rows()) reader.LoadImage(row);
  } catch (const RecordingError& error) {
    return error.what();
  }
  return "";
}

TEST(RecordingSafety, RowPointingOutsideTheRecordingIsAnErrorInCheckAndReader) {
  const std::string dir = CompleteRecording("traversal", kBracketSize);
  WriteText(fs::path(dir) / ".." / "outside.png", Slurp(fs::path(dir) / "frames/000001.png"));
  EditCsvLine(dir, 3, [](std::string line) {
    return std::regex_replace(line, std::regex("frames/000001.png"), "frames/../../../outside.png");
  });
  const RecordingCheck check = CheckRecording(dir);
  EXPECT_FALSE(check.ok());
  EXPECT_NE(check.BriefReport().find("frames.csv:3: bad row: file 'frames/../../../outside.png'"),
            std::string::npos)
      << check.BriefReport();
  EXPECT_NE(ReaderError(dir).find("frames.csv:3"), std::string::npos) << ReaderError(dir);
  fs::remove_all(dir);
}

TEST(RecordingSafety, DotSlashFileIsNotItsOwnFrameName) {
  const std::string dir = CompleteRecording("dotslash", kBracketSize);
  EditCsvLine(dir, 3, [](std::string line) {
    return std::regex_replace(line, std::regex("frames/000001.png"), "frames/./000000.png");
  });
  const RecordingCheck check = CheckRecording(dir);
  EXPECT_NE(check.BriefReport().find("error: frames.csv:3: bad row: file 'frames/./000000.png'"),
            std::string::npos)
      << check.BriefReport();
  EXPECT_FALSE(ReaderError(dir).empty());
  fs::remove_all(dir);
}

TEST(RecordingSafety, FifoInPlaceOfAFrameIsRefusedWithoutBlocking) {
  const std::string dir = CompleteRecording("fifo", kBracketSize);
  const fs::path png = fs::path(dir) / "frames/000002.png";
  fs::remove(png);
  ASSERT_EQ(::mkfifo(png.c_str(), 0644), 0);
  auto checked = std::async(std::launch::async, [&dir] { return CheckRecording(dir); });
  ASSERT_EQ(checked.wait_for(std::chrono::seconds(20)), std::future_status::ready)
      << "check blocked on a FIFO";
  EXPECT_NE(checked.get().BriefReport().find("frames/000002.png: is not a regular file"),
            std::string::npos);
  EXPECT_NE(ReaderError(dir).find("000002.png (frames.csv:4): is not a regular file"),
            std::string::npos)
      << ReaderError(dir);
  fs::remove_all(dir);
}

TEST(RecordingSafety, PngHeaderClaimingAHugeImageIsRefusedBeforeDecoding) {
  const std::string dir = CompleteRecording("hugepng", kBracketSize);
  const fs::path png = fs::path(dir) / "frames/000001.png";
  std::string bytes = Slurp(png);
  for (int offset : {16, 20}) {  // IHDR width and height: 50000 = 0x0000C350
    bytes[offset] = 0;
    bytes[offset + 1] = 0;
    bytes[offset + 2] = static_cast<char>(0xC3);
    bytes[offset + 3] = 0x50;
  }
  WriteText(png, bytes);
  const std::string report = CheckRecording(dir).BriefReport();
  EXPECT_NE(report.find("frames/000001.png: PNG header claims 50000 x 50000 px"), std::string::npos)
      << report;
  EXPECT_NE(ReaderError(dir).find("50000 x 50000"), std::string::npos) << ReaderError(dir);
  fs::remove_all(dir);
}

TEST(RecordingSafety, ImpossibleOrMissingBitDepthIsAnErrorNamingRecordingYaml) {
  const std::string dir = CompleteRecording("bitdepth", kBracketSize);
  const fs::path yaml = fs::path(dir) / "recording.yaml";
  const std::string text = Slurp(yaml);
  WriteText(yaml, std::regex_replace(text, std::regex("bit_depth: 12"), "bit_depth: 40"));
  EXPECT_NE(CheckRecording(dir).BriefReport().find("bit_depth 40 is impossible"),
            std::string::npos)
      << CheckRecording(dir).BriefReport();
  WriteText(yaml, std::regex_replace(text, std::regex("\\s*bit_depth: 12"), ""));
  const std::string error = ReaderError(dir);
  EXPECT_NE(error.find("recording.yaml:"), std::string::npos) << error;
  EXPECT_NE(error.find("missing the key 'bit_depth'"), std::string::npos) << error;
  fs::remove_all(dir);
}

TEST(RecordingSafety, UnknownKeyInRecordingYamlIsAnError) {
  const std::string dir = CompleteRecording("unknownkey", kBracketSize);
  const fs::path yaml = fs::path(dir) / "recording.yaml";
  WriteText(yaml, Slurp(yaml) + "completoin: cut\n");
  EXPECT_NE(ReaderError(dir).find("unknown key 'completoin'"), std::string::npos)
      << ReaderError(dir);
  fs::remove_all(dir);
}

TEST(RecordingSafety, RecipeAndRigTextsAreKeptByteForByte) {
  for (const std::string& recipe :
       {std::string("name: crlf\r\nafter: fit\r\n"), std::string("name: no-final-newline"),
        std::string("  name: indented\n  after: fit\n\n\n"), std::string("")}) {
    const std::string dir = TempDir("bytes");
    RecordingHeader header = TestHeader();
    header.recipe_text = recipe;
    header.rig_text = recipe + "# rig";
    auto writer = RecordingWriter::Open(dir, header);
    WriteFrames(*writer, 0, 1);
    writer->Close(Completion::kCut);
    const RecordingReader reader(dir);
    EXPECT_EQ(reader.header().recipe_text, recipe);
    EXPECT_EQ(reader.header().rig_text, recipe + "# rig");
    EXPECT_EQ(RecordingWriter::Resume(dir)->header().recipe_text, recipe);
    fs::remove_all(dir);
  }
}

TEST(RecordingSafety, EditedRecipeBesideTheRecordingIsRefused) {
  const std::string dir = CompleteRecording("editedrecipe", kBracketSize);
  WriteText(fs::path(dir) / "recipe.yaml", "name: other\n");
  EXPECT_NE(ReaderError(dir).find("recipe.yaml: its CRC-32"), std::string::npos)
      << ReaderError(dir);
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

TEST(RecordingSafety, EmptySlideIsAnErrorNamingFramesCsvLine) {
  const std::string dir = CompleteRecording("emptyslide", kBracketSize);
  EditCsvLine(dir, 4, [](std::string line) {
    return std::regex_replace(line, std::regex(",1500,10,"), ",,10,");
  });
  EXPECT_NE(ReaderError(dir).find("frames.csv:4: bad row: bad slide_mm ''"), std::string::npos)
      << ReaderError(dir);
  fs::remove_all(dir);
}

TEST(RecordingSafety, ParsersRefuseGarbageWithNamedErrors) {
  EXPECT_FALSE(ParseFramesCsv("nonsense\n").errors.empty());
  EXPECT_THROW(ParseRecordingHeader("format: [\n", "recording.yaml"), RecordingError);
  std::string why;
  EXPECT_TRUE(DecodeFramePng({0x89, 'P', 'N', 'G'}, &why).empty());
  EXPECT_NE(why.find("not a PNG"), std::string::npos);
}

// --- Issue 19: content hashes, links, the bit depth -------------------------------------------

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

// The case: two PNGs swapped passed check. Now check, and the reader, name the frames.
TEST(RecordingIntegrity, SwappedPngsAreFoundByCheckAndTheReader) {
  const std::string dir = CompleteRecording("swapped", 2 * kBracketSize);
  const fs::path a = fs::path(dir) / "frames/000002.png";
  const fs::path b = fs::path(dir) / "frames/000007.png";
  const std::string bytes_a = Slurp(a);
  WriteText(a, Slurp(b));
  WriteText(b, bytes_a);
  const std::string report = CheckRecording(dir).BriefReport();
  EXPECT_FALSE(CheckRecording(dir).ok());
  EXPECT_NE(report.find("frames/000002.png: its content is not the frame recorded in its row"),
            std::string::npos) << report;
  EXPECT_NE(report.find("frames/000007.png: its content"), std::string::npos) << report;
  EXPECT_NE(ReaderError(dir).find("frames/000002.png"), std::string::npos) << ReaderError(dir);
  fs::remove_all(dir);
}

// Edited pose columns (with the row's hash intact) passed check: frames.csv's hash finds them.
TEST(RecordingIntegrity, AnEditedFramesCsvOfAClosedRecordingIsAnError) {
  const std::string dir = CompleteRecording("editedcsv", kBracketSize);
  EditCsvLine(dir, 3, [](std::string line) {
    return std::regex_replace(line, std::regex(",1500,10,"), ",1600,10,");
  });
  const std::string report = CheckRecording(dir).BriefReport();
  EXPECT_NE(report.find("error: frames.csv: its SHA-256 is"), std::string::npos) << report;
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

// A recording made before the hashes (format 1: no sha256 column, no frames_csv_sha256) still
// loads and checks clean, with a note; a resume appends format 1 rows to it.
TEST(RecordingIntegrity, AFormat1RecordingStillLoadsWithANote) {
  const std::string dir = CompleteRecording("format1", kBracketSize);
  std::istringstream in(Slurp(fs::path(dir) / "frames.csv"));
  std::string csv, line;
  while (std::getline(in, line)) {  // format 1 ends at status: no time columns, no sha256
    for (int column = 0; column < 3; ++column) line = line.substr(0, line.rfind(','));
    csv += line + "\n";
  }
  WriteText(fs::path(dir) / "frames.csv", csv);
  std::string yaml = Slurp(fs::path(dir) / "recording.yaml");
  yaml = std::regex_replace(yaml, std::regex("format_version: 2"), "format_version: 1");
  yaml = std::regex_replace(yaml, std::regex("frames_csv_sha256: \"[0-9a-f]*\"\n"), "");
  yaml = std::regex_replace(yaml, std::regex("completion: complete"), "completion: cut");
  WriteText(fs::path(dir) / "recording.yaml", yaml);
  const RecordingReader reader(dir);
  EXPECT_EQ(reader.header().format_version, 1);
  EXPECT_EQ(reader.rows().size(), static_cast<size_t>(kBracketSize));
  EXPECT_EQ(reader.rows()[0].sha256, "");
  const RecordingCheck check = CheckRecording(dir);
  EXPECT_TRUE(check.ok()) << check.BriefReport();
  EXPECT_NE(check.BriefReport().find("note: format_version 1 (before content hashes)"),
            std::string::npos) << check.BriefReport();
  auto resumed = RecordingWriter::Resume(dir);
  WriteFrames(*resumed, kBracketSize, 2 * kBracketSize);
  resumed->Close(Completion::kComplete);
  EXPECT_TRUE(CheckRecording(dir).ok()) << CheckRecording(dir).BriefReport();
  EXPECT_EQ(RecordingReader(dir).rows().size(), static_cast<size_t>(2 * kBracketSize));
  fs::remove_all(dir);
}

// The case: bit_depth 16 on a Mono12 recording passed check.
TEST(RecordingIntegrity, BitDepthThatContradictsThePixelFormatFailsCheck) {
  const std::string dir = CompleteRecording("bitdepth16", kBracketSize);
  std::string yaml = Slurp(fs::path(dir) / "recording.yaml");
  WriteText(fs::path(dir) / "recording.yaml",
            std::regex_replace(yaml, std::regex("bit_depth: 12"), "bit_depth: 16"));
  const std::string report = CheckRecording(dir).BriefReport();
  EXPECT_NE(report.find("error: recording.yaml: image.bit_depth 16 contradicts image.pixel_format "
                        "Mono12"), std::string::npos) << report;
  fs::remove_all(dir);
}

// Frames of a bracket in the wrong order (their PNGs and hashes moved with them): the signal
// falls as the exposure grows.
TEST(RecordingIntegrity, ABracketWhoseBrightnessContradictsItsExposuresFailsCheck) {
  const std::string dir = TempDir("ordering");
  auto writer = RecordingWriter::Open(dir, TestHeader());
  for (std::int64_t i = 0; i < kBracketSize; ++i) {
    writer->Append(TestImage(100 * (kBracketSize - i)), TestRecord(i));  // brightest first
  }
  writer->Close(Completion::kComplete);
  const std::string report = CheckRecording(dir).BriefReport();
  EXPECT_NE(report.find("has less signal"), std::string::npos) << report;
  fs::remove_all(dir);
}

// A frames/ that is a link (the issue: check passed, a resume wrote 240 PNGs outside), and a
// recording.yaml that is one: refused by check, the reader and a resume, naming the path.
TEST(RecordingSafety, LinkedFramesFolderOrHeaderIsRefusedEverywhere) {
  for (const std::string part : {"frames", "recording.yaml", "frames.csv"}) {
    const std::string dir = TempDir("linked-" + part);
    auto writer = RecordingWriter::Open(dir, TestHeader());
    WriteFrames(*writer, 0, kBracketSize);
    writer->Close(Completion::kCut);
    const fs::path real = fs::path(dir + "-outside");
    fs::remove_all(real);
    fs::rename(fs::path(dir) / part, real);
    fs::create_symlink(real, fs::path(dir) / part);
    const RecordingCheck check = CheckRecording(dir);
    EXPECT_FALSE(check.ok()) << part;
    EXPECT_NE(check.BriefReport().find(part + " is a symbolic link"), std::string::npos)
        << check.BriefReport();
    EXPECT_NE(ReaderError(dir).find("symbolic link"), std::string::npos) << ReaderError(dir);
    try {
      RecordingWriter::Resume(dir);
      ADD_FAILURE() << "a resume through a linked " << part << " was accepted";
    } catch (const RecordingError& error) {
      EXPECT_NE(std::string(error.what()).find(dir + "/" + part), std::string::npos)
          << error.what();
    }
    fs::remove_all(dir);
    fs::remove_all(real);
  }
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

// frames.csv's line `line` split at commas (an empty last field kept).
std::vector<std::string> CsvFields(const std::string& dir, int line) {
  std::istringstream in(Slurp(fs::path(dir) / "frames.csv"));
  std::string text;
  for (int n = 1; n <= line; ++n) std::getline(in, text);
  std::vector<std::string> fields;
  std::istringstream row(text + ",");
  for (std::string field; std::getline(row, field, ',');) fields.push_back(field);
  return fields;
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

TEST(RecordingTime, UtcTimeThatIsNotTheHostTimeIsAnErrorNamingTheLine) {
  const std::string dir = CompleteRecording("badutc", kBracketSize);
  EditCsvLine(dir, 3, [](std::string line) {
    return std::regex_replace(line, std::regex("2023-11-14T22:13:20"), "2023-11-14T22:13:21");
  });
  EXPECT_NE(ReaderError(dir).find("frames.csv:3: bad row: bad utc_time"), std::string::npos)
      << ReaderError(dir);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace irdist
