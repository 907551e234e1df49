// `irdist check` on damaged recordings: corrupt PNGs, bad rows, gaps and orphans by file and line,
// swapped or edited frames and rows, a bit depth or brightness that contradicts the header, links.
#include "acquisition/recording_check.h"

#include <gtest/gtest.h>
#include <signal.h>

#include <filesystem>
#include <fstream>
#include <regex>

#include "acquisition/recording_reader.h"
#include "acquisition/recording_writer.h"
#include "tests/acquisition/recording_helpers.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;

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

// The issue's case: two PNGs swapped passed check. Now check, and the reader, name the frames.
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

// The issue's case: bit_depth 16 on a Mono12 recording passed check.
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

// The issue: check on a recording a live calibrate was writing said "the writer died".
TEST(RecordingLive, ARecordingBeingWrittenIsNamedWithItsWriterNeverAsDead) {
  const std::string dir = TempDir("livecheck");
  auto writer = RecordingWriter::Open(dir, TestHeader());
  WriteFrames(*writer, 0, kBracketSize);
  const RecordingCheck check = CheckRecording(dir);
  const std::string report = check.BriefReport();
  EXPECT_EQ(check.live_writer, std::to_string(getpid()));
  EXPECT_NE(report.find("being written by process " + std::to_string(getpid())),
            std::string::npos) << report;
  EXPECT_EQ(report.find("died"), std::string::npos) << report;
  writer.reset();  // killed: the lock is released, the header stays "running"
  const std::string dead = CheckRecording(dir).BriefReport();
  EXPECT_NE(dead.find("the writer died"), std::string::npos) << dead;
  EXPECT_NE(dead.find("UNVERIFIED: frames.csv has no hash"), std::string::npos) << dead;
  EXPECT_TRUE(CheckRecording(dir).ok()) << dead;
  fs::remove_all(dir);
}

// The issue: a closed header set to what a kill -9 leaves (running, no hash) let edited rows pass.
TEST(RecordingIntegrity, AClosedHeaderMadeToLookKilledIsAnError) {
  const std::string dir = CompleteRecording("fakekill", kBracketSize);
  std::string yaml = Slurp(fs::path(dir) / "recording.yaml");
  yaml = std::regex_replace(yaml, std::regex("completion: complete"), "completion: running");
  yaml = std::regex_replace(yaml, std::regex("frames_csv_sha256: \"[0-9a-f]+\""),
                            "frames_csv_sha256: \"\"");
  WriteText(fs::path(dir) / "recording.yaml", yaml);
  const std::string report = CheckRecording(dir).BriefReport();
  EXPECT_NE(report.find("error: recording.yaml: completion is 'running' but end_time and "
                        "frame_count are set"), std::string::npos) << report;
  fs::remove_all(dir);
}

// The issue: a header downgraded to format 1 let edited rows and frames pass unverified.
TEST(RecordingIntegrity, AHeaderDowngradedToFormat1IsAnError) {
  const std::string dir = CompleteRecording("downgrade", kBracketSize);
  const std::string yaml = Slurp(fs::path(dir) / "recording.yaml");
  WriteText(fs::path(dir) / "recording.yaml",
            std::regex_replace(yaml, std::regex("format_version: 2"), "format_version: 1"));
  const std::string report = CheckRecording(dir).BriefReport();
  EXPECT_NE(report.find("error: recording.yaml: format_version 1 (before content hashes) but "
                        "frames.csv has format 2's sha256 column"), std::string::npos) << report;
  fs::remove_all(dir);
}

// The issue: a row at another slide position than its bracket's siblings was never checked.
TEST(RecordingIntegrity, ARowAtAnotherPoseThanItsBracketIsAnError) {
  const std::string dir = CompleteRecording("pose", 2 * kBracketSize);
  EditCsvLine(dir, 4, [](std::string line) {  // frame 2 of bracket 0 at slide 1500
    return std::regex_replace(line, std::regex(",1500,10,"), ",1600,10,");
  });
  const RecordingCheck check = CheckRecording(dir);
  const std::string report = check.BriefReport();
  EXPECT_NE(report.find("error: frames.csv:4: bracket 0: frames/000002.png is at slide 1600 mm"),
            std::string::npos) << report;
  EXPECT_NE(report.find("not at its bracket's pose and current (those of frames/000000.png at "
                        "frames.csv:2)"), std::string::npos) << report;
  EXPECT_EQ(report.find("frames.csv:3: bracket"), std::string::npos) << report;
  fs::remove_all(dir);
}

// The issue: a wrong-size frame 0 made check blame the 95 good frames after it.
TEST(Recording, AFrameOfAnotherSizeThanMostIsTheOneBlamed) {
  const std::string dir = TempDir("oddsize");
  auto writer = RecordingWriter::Open(dir, TestHeader());
  writer->Append(cv::Mat(12, 16, CV_16UC1, cv::Scalar(0)), TestRecord(0));
  WriteFrames(*writer, 1, 2 * kBracketSize);
  writer->Close(Completion::kComplete);
  const RecordingCheck check = CheckRecording(dir);
  int size_errors = 0;
  for (const RecordingIssue& issue : check.errors) {
    if (issue.message.find("size") == std::string::npos) continue;
    ++size_errors;
    EXPECT_EQ(issue.file, "frames/000000.png");
    EXPECT_NE(issue.message.find("its size 16 x 12 px differs from the 32 x 24 px of the "
                                 "recording's other frames"), std::string::npos) << issue.message;
  }
  EXPECT_EQ(size_errors, 1) << check.BriefReport();
  fs::remove_all(dir);
}

// The issue: BayerRG8, or Mono16 over a camera that read back Mono12, passed check.
TEST(RecordingIntegrity, APixelFormatThatIsNotTheCamerasOrUnknownFailsCheck) {
  const std::string dir = CompleteRecording("pixfmt", kBracketSize);
  const std::string yaml = Slurp(fs::path(dir) / "recording.yaml");
  WriteText(fs::path(dir) / "recording.yaml",
            std::regex_replace(std::regex_replace(yaml, std::regex("bit_depth: 12"),
                                                  "bit_depth: 16"),
                               std::regex("pixel_format: Mono12"), "pixel_format: Mono16"));
  std::string report = CheckRecording(dir).BriefReport();
  EXPECT_NE(report.find("error: recording.yaml: image.pixel_format Mono16 contradicts the "
                        "camera's camera.features.PixelFormat Mono12"), std::string::npos)
      << report;
  WriteText(fs::path(dir) / "recording.yaml",
            std::regex_replace(yaml, std::regex("pixel_format: Mono12"), "pixel_format: BayerRG8"));
  report = CheckRecording(dir).BriefReport();
  EXPECT_NE(report.find("error: recording.yaml: image.pixel_format BayerRG8 is not a format irdist "
                        "records"), std::string::npos) << report;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace irdist
