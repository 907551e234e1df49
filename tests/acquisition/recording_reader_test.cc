// The recording's reader and parsers: round trip, rows that name a file outside the recording or a
// FIFO, oversized PNGs, strict recording.yaml, the recipe and rig texts kept byte for byte, a
// format 1 recording, bad time columns.
#include "acquisition/recording_reader.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <future>
#include <regex>
#include <sstream>

#include "acquisition/recording_check.h"
#include "acquisition/recording_writer.h"
#include "tests/acquisition/recording_helpers.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;

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
  EXPECT_NE(CheckRecording(dir).BriefReport().find("bit_depth = 40 is outside [1, 16] bit"),
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

TEST(RecordingSafety, EmptySlideIsAnErrorNamingFramesCsvLine) {
  const std::string dir = CompleteRecording("emptyslide", kBracketSize);
  EditCsvLine(dir, 4, [](std::string line) {
    return std::regex_replace(line, std::regex(",1500,10,"), ",,10,");
  });
  EXPECT_NE(ReaderError(dir).find("frames.csv:4: bad row: bad slide_mm ''"), std::string::npos)
      << ReaderError(dir);
  fs::remove_all(dir);
}

TEST(RecordingBounds, RowNumberOutsideTheTableIsRefusedNamingLineColumnAndRange) {
  const std::string dir = CompleteRecording("rowbounds", kBracketSize);
  EditCsvLine(dir, 4, [](std::string line) {
    return std::regex_replace(line, std::regex(",1500,10,"), ",1e9,10,");
  });
  const std::string expected =
      "frames.csv:4: bad row: slide_mm = 1000000000 is outside [-100000, 100000] mm";
  EXPECT_NE(ReaderError(dir).find(expected), std::string::npos) << ReaderError(dir);
  // check lists it as one more error, the other rows still read.
  const std::string report = CheckRecording(dir).BriefReport();
  EXPECT_NE(report.find("frames.csv:4: bad row: slide_mm = 1000000000 is outside"),
            std::string::npos)
      << report;
  fs::remove_all(dir);
}

TEST(RecordingBounds, HeaderCountOutsideTheTableIsRefusedNamingLineAndRange) {
  const std::string dir = CompleteRecording("headerbounds", kBracketSize);
  const fs::path yaml = fs::path(dir) / "recording.yaml";
  WriteText(yaml, std::regex_replace(Slurp(yaml), std::regex("frame_count: [0-9]+"),
                                     "frame_count: 1e300"));
  const std::string error = ReaderError(dir);
  EXPECT_NE(error.find("recording.yaml:"), std::string::npos) << error;
  EXPECT_NE(error.find("frame_count = 1e+300 is outside [0, 1000000000]"), std::string::npos)
      << error;
  EXPECT_NE(CheckRecording(dir).BriefReport().find("frame_count = 1e+300 is outside"),
            std::string::npos)
      << CheckRecording(dir).BriefReport();
  fs::remove_all(dir);
}

TEST(RecordingSafety, ParsersRefuseGarbageWithNamedErrors) {
  EXPECT_FALSE(ParseFramesCsv("nonsense\n").errors.empty());
  EXPECT_THROW(ParseRecordingHeader("format: [\n", "recording.yaml"), RecordingError);
  std::string why;
  EXPECT_TRUE(DecodeFramePng({0x89, 'P', 'N', 'G'}, &why).empty());
  EXPECT_NE(why.find("not a PNG"), std::string::npos);
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
