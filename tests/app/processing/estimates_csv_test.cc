// estimates.csv's standard errors and flags: written, read back, older files still read, an
// unknown flag refused with its line, and what makes a row trusted.
#include "app/processing/estimates_csv.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "base/utc_time.h"
#include "tests/app/processing/hand_made_estimates.h"
#include "tests/full_disk.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;

class EstimatesCsvTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("irdist_estimates_csv_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string Path(const char* name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

EstimateRow Row(double d_mm, std::vector<EstimateFlag> flags) {
  EstimateRow r;
  r.method = "i0_free";
  r.true_d_mm = 2000.0;
  r.true_theta_deg = 10.0;
  r.bias_ma = 500.0;
  r.d_mm = d_mm;
  r.theta_deg = 10.1;
  r.d_std_mm = 1.25;
  r.theta_std_deg = 0.5;
  r.flags = std::move(flags);
  return r;
}

TEST_F(EstimatesCsvTest, StandardErrorsAndFlagsRoundTrip) {
  std::vector<EstimateRow> rows = {
      Row(2001.0, {}),
      Row(2003.0, {{"defect_pixels", "3"}, {"t_meas_extrapolated", "40.0ms"}}),
      Row(2400.0, {{"second_source", "6.5px"}, {"outside", "distance+theta"}})};
  rows[2].ok = false;  // no estimate: its standard errors are not written
  WriteEstimatesCsv(Path("e.csv"), rows);
  const std::vector<EstimateRow> again = ReadEstimatesCsv(Path("e.csv"));
  ASSERT_EQ(again.size(), 3u);
  EXPECT_DOUBLE_EQ(again[0].d_std_mm, 1.25);
  EXPECT_DOUBLE_EQ(again[0].theta_std_deg, 0.5);
  EXPECT_TRUE(again[0].flags.empty());
  EXPECT_EQ(again[1].flags, rows[1].flags);
  EXPECT_EQ(again[2].flags, rows[2].flags);
  EXPECT_LT(again[2].d_std_mm, 0.0);
  std::ifstream in(Path("e.csv"));
  std::string header, first, second;
  std::getline(in, header);
  std::getline(in, first);
  std::getline(in, second);
  EXPECT_NE(header.find(",d_se_mm,theta_se_deg,flags"), std::string::npos) << header;
  EXPECT_NE(second.find(",1.25,0.5,defect_pixels=3 t_meas_extrapolated=40.0ms"),
            std::string::npos)
      << second;
}

TEST_F(EstimatesCsvTest, NotesLeaveARowTrustedAndAnyOtherFlagDoesNot) {
  EXPECT_TRUE(Row(2001.0, {}).Trusted());
  EXPECT_TRUE(Row(2001.0, {{"defect_pixels", "2"}, {"other_blobs", "1"}}).Trusted());
  EXPECT_FALSE(Row(2001.0, {{"occluded", "18%"}}).Trusted());
  EXPECT_FALSE(Row(2001.0, {{"second_source", "3.0px"}}).Trusted());
  EstimateRow none = Row(2001.0, {});
  none.ok = false;
  EXPECT_FALSE(none.Trusted());
  for (const FlagSpec& spec : FlagSpecs()) {
    EXPECT_EQ(FindFlagSpec(spec.name), &spec);
    EXPECT_GT(std::string(spec.meaning).size(), 10u) << spec.name;
  }
  EXPECT_EQ(FindFlagSpec("ok"), nullptr);
}

TEST_F(EstimatesCsvTest, AFileBeforeTheFlagsIsStillRead) {
  WriteEstimatesCsv(Path("new.csv"), {Row(2001.0, {{"defect_pixels", "1"}})});
  std::ifstream in(Path("new.csv"));
  std::string header, row;
  std::getline(in, header);
  std::getline(in, row);
  // Drop the last three columns, as a file written before them.
  const auto cut = [](std::string line) {
    for (int i = 0; i < 3; ++i) line = line.substr(0, line.rfind(','));
    return line;
  };
  std::ofstream(Path("old.csv")) << cut(header) << "\n" << cut(row) << "\n";
  const std::vector<EstimateRow> old = ReadEstimatesCsv(Path("old.csv"));
  ASSERT_EQ(old.size(), 1u);
  EXPECT_DOUBLE_EQ(old[0].d_mm, 2001.0);
  EXPECT_TRUE(old[0].flags.empty());
  EXPECT_LT(old[0].d_std_mm, 0.0);
}

TEST_F(EstimatesCsvTest, AnUnknownFlagIsRefusedWithItsLine) {
  WriteEstimatesCsv(Path("e.csv"), {Row(2001.0, {{"occluded", "20%"}})});
  std::ifstream in(Path("e.csv"));
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  text.replace(text.find("occluded=20%"), 12, "sunny=20%");
  std::ofstream(Path("bad.csv")) << text;
  try {
    ReadEstimatesCsv(Path("bad.csv"));
    FAIL() << "an unknown flag was read";
  } catch (const EstimatesFileError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.csv:2: flag 'sunny'"), std::string::npos)
        << e.what();
  }
}

// The issue: measure on a full disk left an empty estimates.csv, and its rerun was refused for it.
TEST_F(EstimatesCsvTest, AHeaderThatCannotBeWrittenLeavesNoFile) {
  std::string error;
  try {
    const testing::FullDisk full;
    EstimatesCsvWriter writer(Path("estimates.csv"));
  } catch (const EstimatesFileError& e) {
    error = e.what();
  }
  EXPECT_NE(error.find("write failed"), std::string::npos) << error;
  EXPECT_FALSE(fs::exists(Path("estimates.csv")));
}

// The hand-made estimates.csv (tests/app/processing/hand_made_estimates.h): every column
// read back as written, and the rows the summary counts.
// One line of a text file, for istream_iterator.
struct Line : std::string {
  friend std::istream& operator>>(std::istream& in, Line& line) { return std::getline(in, line); }
};

TEST_F(HandMadeEstimatesTest, RoundTripKeepsEveryRow) {
  const auto rows = ReadEstimatesCsv((dir_ / "estimates.csv").string());
  const std::string path = (dir_ / "copy.csv").string();
  WriteEstimatesCsv(path, rows);
  const auto again = ReadEstimatesCsv(path);
  ASSERT_EQ(again.size(), rows.size());
  for (size_t i = 0; i < rows.size(); ++i) {
    EXPECT_EQ(again[i].method, rows[i].method);
    EXPECT_EQ(again[i].d_mm, rows[i].d_mm);
    EXPECT_EQ(again[i].outside_range, rows[i].outside_range);
  }
}

TEST_F(HandMadeEstimatesTest, PositionColumnsRoundTripAndUnknownTruthIsEmpty) {
  std::vector<EstimateRow> rows = ReadEstimatesCsv((dir_ / "estimates.csv").string());
  ASSERT_GE(rows.size(), 2u);
  rows[0].x_mm = 12.5;
  rows[0].z_se_mm = 3.25;
  rows[0].true_x_mm = 12.0;
  rows[1].true_d_mm = NAN;  // irdist measure without a pose
  const std::string path = (dir_ / "xyz.csv").string();
  WriteEstimatesCsv(path, rows);
  std::ifstream in(path);
  std::string header, first, second;
  std::getline(in, header);
  std::getline(in, first);
  std::getline(in, second);
  EXPECT_NE(header.find(",x_mm,y_mm,z_mm,x_se_mm,y_se_mm,z_se_mm,true_x_mm,true_y_mm,true_z_mm"),
            std::string::npos);
  EXPECT_NE(first.find(",12.5,,,,,3.25,12,,"), std::string::npos) << first;
  EXPECT_NE(second.find(",i0_free,0,,"), std::string::npos) << second;
  rows.erase(rows.begin() + 1);
  WriteEstimatesCsv(path, rows);
  const std::vector<EstimateRow> again = ReadEstimatesCsv(path);
  EXPECT_EQ(again[0].x_mm, 12.5);
  EXPECT_EQ(again[0].true_x_mm, 12.0);
  EXPECT_TRUE(std::isnan(again[0].y_mm));
}

// estimates.csv as irdist measure writes it, bracket by bracket: every appended row reads back;
// a last line torn by a crash (no end of line) is dropped, and the note names its line.
TEST_F(HandMadeEstimatesTest, StreamedRowsReadBackAndATornLastLineIsDroppedWithANote) {
  const std::vector<EstimateRow> rows = ReadEstimatesCsv((dir_ / "estimates.csv").string());
  ASSERT_EQ(rows.size(), 9u);
  const std::string path = (dir_ / "streamed.csv").string();
  {
    EstimatesCsvWriter writer(path);
    writer.Append({rows.begin(), rows.begin() + 4});
    EXPECT_EQ(ReadEstimatesCsv(path).size(), 4u);  // on disk before the next append
    writer.Append({rows.begin() + 4, rows.end()});
  }
  std::string note = "stale";
  EXPECT_EQ(ReadEstimatesCsv(path, &note).size(), 9u);
  EXPECT_EQ(note, "");
  std::ofstream(path, std::ios::app) << "6,3,0,i0_free,0,1500,0,5";  // killed while writing
  const std::vector<EstimateRow> again = ReadEstimatesCsv(path, &note);
  ASSERT_EQ(again.size(), 9u);
  EXPECT_EQ(again.back().bracket, 5);
  EXPECT_NE(note.find("streamed.csv:11"), std::string::npos) << note;
  EXPECT_NE(note.find("torn"), std::string::npos) << note;
  EXPECT_EQ(ReadEstimatesCsv(path).size(), 9u);  // also without asking for the note
}

// The bracket's time: UTC as ISO 8601 with microseconds, the monotonic clock and the camera's
// timestamp (all 64 bits), empty when unknown; unknown ground truth (measure without --at) reads
// as NaN.
TEST_F(HandMadeEstimatesTest, TimeColumnsRoundTripAndUnknownValuesAreEmpty) {
  std::vector<EstimateRow> rows = ReadEstimatesCsv((dir_ / "estimates.csv").string());
  const std::optional<std::int64_t> utc_ns = ParseUtcIso8601("2026-12-02T06:12:03.123456Z");
  ASSERT_TRUE(utc_ns.has_value());
  rows[0].utc_ns = *utc_ns;
  rows[0].host_monotonic_ns = 987654321012345;
  rows[0].camera_timestamp_ns = 18446744073709551000ull;
  rows[1].true_d_mm = rows[1].true_theta_deg = rows[1].bias_ma = NAN;
  const std::string path = (dir_ / "times.csv").string();
  WriteEstimatesCsv(path, rows);
  std::ifstream in(path);
  const std::vector<std::string> lines{std::istream_iterator<Line>(in),
                                       std::istream_iterator<Line>()};
  ASSERT_EQ(lines.size(), rows.size() + 1);
  EXPECT_NE(lines[0].find(",outside,utc_time,host_monotonic_ns,camera_timestamp_ns"),
            std::string::npos)
      << lines[0];
  EXPECT_NE(lines[1].find(",2026-12-02T06:12:03.123456Z,987654321012345,18446744073709551000"),
            std::string::npos)
      << lines[1];
  EXPECT_EQ(lines[2].substr(lines[2].size() - 3), ",,,") << lines[2];
  const std::vector<EstimateRow> again = ReadEstimatesCsv(path);
  EXPECT_EQ(again[0].utc_ns, *utc_ns);
  EXPECT_EQ(again[0].host_monotonic_ns, 987654321012345);
  EXPECT_EQ(again[0].camera_timestamp_ns, 18446744073709551000ull);
  EXPECT_EQ(again[1].utc_ns, 0);
  EXPECT_EQ(again[1].camera_timestamp_ns, 0u);
  EXPECT_TRUE(std::isnan(again[1].true_d_mm));
  EXPECT_TRUE(std::isnan(again[1].bias_ma));
}

// estimates.csv is never written through a link planted at its name: the link's target is kept.
TEST_F(HandMadeEstimatesTest, EstimatesCsvIsNeverWrittenThroughALink) {
  const fs::path victim = dir_ / "victim.txt";
  std::ofstream(victim) << "precious\n";
  fs::create_symlink(victim, dir_ / "linked.csv");
  EXPECT_THROW(EstimatesCsvWriter((dir_ / "linked.csv").string()), EstimatesFileError);
  std::ifstream in(victim);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text, "precious\n");
}

TEST_F(HandMadeEstimatesTest, BadRowIsRefusedWithItsLine) {
  std::ofstream(dir_ / "bad.csv") << "bracket,pose,repeat,method,dt_ms,true_d_mm,true_theta_deg,"
                                     "bias_ma,d_mm,theta_deg,outside_range,ok\n"
                                     "0,0,0,i0_free,0,2000,20,475,2010,21,0,1\n"
                                     "1,0,1,i0_free,0,2000,20,475,abc,19.5,0,1\n";
  try {
    ReadEstimatesCsv((dir_ / "bad.csv").string());
    FAIL() << "a non-numeric d_mm was accepted";
  } catch (const EstimatesFileError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.csv:3"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("d_mm"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace irdist
