// The checks of acquisition/recording_integrity.h on hand-made rows and signals: the bit depth
// against the pixel format, values beyond it, and a bracket whose signal falls as its exposure
// grows.
#include "acquisition/recording_integrity.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "acquisition/content_hash.h"

namespace irdist {
namespace {

FrameRecord Row(std::int64_t index, double exposure_us, int line) {
  FrameRecord r;
  r.index = index;
  r.file = "frames/00000" + std::to_string(index) + ".png";
  r.actual_exposure_us = exposure_us;
  r.line = line;
  return r;
}

TEST(RecordingIntegrity, BitDepthMustBeThePixelFormats) {
  RecordingHeader header;
  header.pixel_format = "Mono12";
  header.bit_depth = 16;
  const auto issues = PixelFormatIssues(header);
  ASSERT_EQ(issues.size(), 1u);
  EXPECT_EQ(issues[0].file, "recording.yaml");
  EXPECT_NE(issues[0].message.find("bit_depth: 12"), std::string::npos) << issues[0].message;
  header.bit_depth = 12;
  EXPECT_TRUE(PixelFormatIssues(header).empty());
  header.pixel_format = "Mono12p";  // packed: 12 bits too
  EXPECT_TRUE(PixelFormatIssues(header).empty());
  header.pixel_format = "BayerRG8";  // not a format irdist records
  ASSERT_EQ(PixelFormatIssues(header).size(), 1u);
  EXPECT_NE(PixelFormatIssues(header)[0].message.find("not a format irdist records"),
            std::string::npos);
  header.pixel_format = "Mono12";
  header.camera_features["PixelFormat"] = "Mono12Packed";  // the camera's read-back differs
  ASSERT_EQ(PixelFormatIssues(header).size(), 1u);
  header.pixel_format.clear();  // a hand-made header without one: not checked
  EXPECT_TRUE(PixelFormatIssues(header).empty());
  EXPECT_EQ(BitsOfMonoFormat("Mono8"), 8);
  EXPECT_EQ(BitsOfMonoFormat("Mono16"), 16);
  EXPECT_EQ(BitsOfMonoFormat("Mono9"), 0);
}

TEST(RecordingIntegrity, EveryRowOfABracketHasItsPoseAndCurrent) {
  RecordedBracket bracket;
  bracket.bracket_id = 7;
  for (int k = 0; k < 3; ++k) {
    FrameRecord r = Row(k, 8000 + 1000 * k, k + 2);
    r.slide_mm = 1500;
    r.bias_ma_set = 20;
    r.bias_ma_measured = 19.9 + 0.01 * k;  // measured, not set: may differ
    bracket.frames.push_back(r);
  }
  EXPECT_TRUE(BracketPoseIssues({bracket}).empty());
  bracket.frames[2].bias_ma_set = 21;
  const auto issues = BracketPoseIssues({bracket});
  ASSERT_EQ(issues.size(), 1u);
  EXPECT_EQ(issues[0].line, 4);
  EXPECT_NE(issues[0].message.find("bracket 7"), std::string::npos) << issues[0].message;
}

TEST(RecordingIntegrity, AValueBeyondTheBitDepthNamesTheFrame) {
  const std::vector<FrameRecord> rows = {Row(0, 8000, 2), Row(1, 30000, 3)};
  const std::map<std::int64_t, FrameSignal> signals = {{0, {1e6, 4095}}, {1, {2e6, 4096}}};
  const auto issues = ValueRangeIssues(rows, signals, 12);
  ASSERT_EQ(issues.size(), 1u);
  EXPECT_EQ(issues[0].file, rows[1].file);
  EXPECT_NE(issues[0].message.find("4096"), std::string::npos) << issues[0].message;
  EXPECT_TRUE(ValueRangeIssues(rows, signals, 16).empty());
}

RecordedBracket BracketOf(const std::vector<FrameRecord>& rows) {
  RecordedBracket bracket;
  bracket.bracket_id = 7;
  bracket.bracket_size = static_cast<int>(rows.size());
  bracket.frames = rows;
  bracket.complete = true;
  return bracket;
}

// Two frames of a bracket swapped: the 36 ms frame holds the 8 ms frame's signal.
TEST(RecordingIntegrity, ABracketWhoseSignalFallsAsItsExposureGrowsIsFlagged) {
  const std::vector<FrameRecord> rows = {Row(0, 8000, 2), Row(1, 30000, 3), Row(2, 36000, 4)};
  const std::map<std::int64_t, FrameSignal> ordered = {
      {0, {1.0e6, 900}}, {1, {3.0e6, 3000}}, {2, {3.5e6, 3500}}};
  EXPECT_TRUE(ExposureOrderIssues({BracketOf(rows)}, ordered).empty());
  const std::map<std::int64_t, FrameSignal> swapped = {
      {0, {3.5e6, 3500}}, {1, {3.0e6, 3000}}, {2, {1.0e6, 900}}};
  const auto issues = ExposureOrderIssues({BracketOf(rows)}, swapped);
  ASSERT_EQ(issues.size(), 1u);  // one per bracket
  EXPECT_EQ(issues[0].file, "frames.csv");
  EXPECT_EQ(issues[0].line, 3);
  EXPECT_NE(issues[0].message.find("bracket 7"), std::string::npos) << issues[0].message;
}

// Equal exposures (a retaken reference) and a dark bracket whose sums differ by noise only.
TEST(RecordingIntegrity, NoiseAndEqualExposuresAreNotFlagged) {
  const std::vector<FrameRecord> rows = {Row(0, 8000, 2), Row(1, 30000, 3), Row(2, 8000, 4)};
  const std::map<std::int64_t, FrameSignal> dark = {
      {0, {4.200e6, 80}}, {1, {4.195e6, 81}}, {2, {4.21e6, 80}}};
  EXPECT_TRUE(ExposureOrderIssues({BracketOf(rows)}, dark).empty());
}

TEST(RecordingIntegrity, ALinkedPartOfTheRecordingIsNamed) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("irdist-integrity-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir / "frames");
  std::ofstream(dir / "recording.yaml") << "format: irdist-recording\n";
  EXPECT_EQ(LinkedRecordingPart(dir.string()), "");
  fs::rename(dir / "frames", dir / "elsewhere");
  fs::create_directory_symlink(dir / "elsewhere", dir / "frames");
  EXPECT_EQ(LinkedRecordingPart(dir.string()), "frames");
  EXPECT_NE(LinkedPartMessage(dir.string(), "frames").find((dir / "frames").string() +
                                                          " is a symbolic link"),
            std::string::npos);
  fs::remove_all(dir);
}

TEST(RecordingIntegrity, FramesCsvIsTheOneClosedOrANoteForFormat1) {
  RecordingHeader header;
  header.completion = Completion::kComplete;
  header.frames_csv_sha256 = Sha256Hex("index,...\n");
  RecordingCheck check;
  AddCsvHashIssues(header, "index,...\n", &check);
  EXPECT_TRUE(check.errors.empty() && check.warnings.empty()) << check.BriefReport();
  AddCsvHashIssues(header, "index,...\nedited\n", &check);
  ASSERT_EQ(check.errors.size(), 1u);
  EXPECT_EQ(check.errors[0].file, "frames.csv");
  header.frames_csv_sha256.clear();  // a closed format 2 header without it
  AddCsvHashIssues(header, "index,...\n", &check);
  EXPECT_EQ(check.errors.size(), 2u);
  header.format_version = 1;
  AddCsvHashIssues(header, "index,...\n", &check);
  ASSERT_EQ(check.warnings.size(), 1u);
  EXPECT_NE(check.warnings[0].message.find("note: format_version 1"), std::string::npos);
}

}  // namespace
}  // namespace irdist
