// estimates.csv's standard errors and flags: written, read back, older files still read, an
// unknown flag refused with its line, and what makes a row trusted.
#include "app/processing/estimates_csv.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

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

}  // namespace
}  // namespace irdist
