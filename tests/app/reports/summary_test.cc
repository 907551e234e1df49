#include "app/reports/summary.h"

#include "app/reports/crb.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cmath>
#include <yaml-cpp/yaml.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <vector>

#include "base/utc_time.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;

// A hand-made estimates.csv. Pose 0: 2000 mm, 20 deg, two currents, two repeats each; pose 1:
// 1500 mm, 0 deg, one current, with per-dt rows (22 and 24 ms) beside its joint row.
constexpr const char* kCsv =
    "bracket,pose,repeat,method,dt_ms,true_d_mm,true_theta_deg,bias_ma,d_mm,theta_deg,"
    "outside_range,ok\n"
    "0,0,0,i0_free,0,2000,20,475,2010,21,0,1\n"
    "1,0,1,i0_free,0,2000,20,475,1990,19.5,0,1\n"
    "2,1,0,i0_free,0,2000,20,525,2020,20,0,1\n"
    "3,1,1,i0_free,0,2000,20,525,2000,22,0,1\n"
    "4,2,0,i0_free,0,1500,0,500,1530,5,1,1\n"
    "4,2,0,i0_free,22,1500,0,500,1515,4,0,1\n"
    "4,2,0,i0_free,24,1500,0,500,1503,3,0,1\n"
    "4,2,0,geometric,0,1500,0,500,1485,0,0,1\n"
    "5,2,1,geometric,0,1500,0,500,0,0,0,0\n";

// One line of a text file, for istream_iterator.
struct Line : std::string {
  friend std::istream& operator>>(std::istream& in, Line& line) { return std::getline(in, line); }
};

class SummaryTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("irdist_summary_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    std::ofstream(dir_ / "estimates.csv") << kCsv;
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(SummaryTest, FiguresMatchHandComputedValues) {
  const auto rows = ReadEstimatesCsv((dir_ / "estimates.csv").string());
  ASSERT_EQ(rows.size(), 9u);
  const ValidationSummary s = Summarize(rows);
  ASSERT_EQ(s.methods.size(), 2u);
  const MethodSummary& m = s.methods[0];
  EXPECT_EQ(m.method, "i0_free");
  // Joint rows only: relative errors 0.5, 0.5, 1.0, 0.0, 2.0 %.
  EXPECT_EQ(m.all.count, 5);
  EXPECT_NEAR(m.all.distance_rel_error_pct_median, 0.5, 1e-12);
  EXPECT_NEAR(m.all.distance_rel_error_pct_p95, 1.8, 1e-12);  // 1 + 0.8 * (2 - 1)
  EXPECT_NEAR(m.all.distance_rel_error_pct_max, 2.0, 1e-12);
  EXPECT_NEAR(m.all.distance_abs_error_mm_median, 10.0, 1e-9);
  EXPECT_NEAR(m.all.distance_abs_error_mm_max, 30.0, 1e-9);
  EXPECT_NEAR(m.all.theta_abs_error_deg_median, 1.0, 1e-12);
  EXPECT_NEAR(m.all.theta_abs_error_deg_max, 5.0, 1e-12);
  EXPECT_EQ(m.all.theta_ge15_count, 4);
  EXPECT_NEAR(m.all.theta_ge15_abs_error_deg_median, 0.75, 1e-12);
  EXPECT_NEAR(m.all.theta_ge15_abs_error_deg_max, 2.0, 1e-12);
  EXPECT_EQ(m.all.theta_lt15_count, 1);
  EXPECT_NEAR(m.all.theta_lt15_abs_error_deg_max, 5.0, 1e-12);
  // Means 2000 (475 mA) and 2010 (525 mA) at 2000 mm: 0.5 %.
  ASSERT_TRUE(m.current_shift_pct.has_value());
  EXPECT_NEAR(*m.current_shift_pct, 0.5, 1e-12);
  // Repeats 2010/1990 and 2020/2000: sample sd sqrt(200) mm.
  ASSERT_TRUE(m.dispersion_mm.has_value());
  EXPECT_NEAR(*m.dispersion_mm, std::sqrt(200.0), 1e-9);
  ASSERT_EQ(m.by_dt.size(), 2u);
  EXPECT_NEAR(m.by_dt.at(22.0).distance_rel_error_pct_max, 1.0, 1e-12);
  EXPECT_NEAR(m.by_dt.at(24.0).distance_rel_error_pct_max, 0.2, 1e-12);
  ASSERT_TRUE(m.best_dt_ms.has_value());
  EXPECT_EQ(*m.best_dt_ms, 24.0);
  EXPECT_EQ(m.outside_calibrated_range, 1);

  const MethodSummary* g = s.Find("geometric");
  ASSERT_NE(g, nullptr);
  EXPECT_EQ(g->all.count, 1);
  EXPECT_EQ(g->all.failed, 1);
  EXPECT_NEAR(g->all.distance_rel_error_pct_max, 1.0, 1e-12);
  EXPECT_FALSE(g->current_shift_pct.has_value());
  EXPECT_FALSE(g->dispersion_mm.has_value());
}

TEST_F(SummaryTest, SummaryYamlHasTheDocumentedKeys) {
  const auto s = Summarize(ReadEstimatesCsv((dir_ / "estimates.csv").string()));
  const std::string path = (dir_ / "summary.yaml").string();
  WriteSummaryYaml(path, s, {{"recipe", "hand-made"}});
  const YAML::Node y = YAML::LoadFile(path);
  EXPECT_EQ(y["recipe"].as<std::string>(), "hand-made");
  EXPECT_EQ(y["count"].as<int>(), 5);
  EXPECT_NEAR(y["distance_rel_error_pct"]["p95"].as<double>(), 1.8, 1e-6);
  EXPECT_NEAR(y["distance_abs_error_mm"]["max"].as<double>(), 30.0, 1e-6);
  EXPECT_NEAR(y["theta_abs_error_deg"]["theta_ge_15"]["median"].as<double>(), 0.75, 1e-6);
  EXPECT_NEAR(y["current_shift_pct"].as<double>(), 0.5, 1e-6);
  EXPECT_NEAR(y["dispersion_mm"].as<double>(), std::sqrt(200.0), 1e-4);
  EXPECT_NEAR(y["by_dt"][22.0]["distance_rel_error_pct"]["max"].as<double>(), 1.0, 1e-6);
  EXPECT_EQ(y["best_dt_ms"].as<double>(), 24.0);
  EXPECT_EQ(y["outside_calibrated_range"].as<int>(), 1);
  EXPECT_EQ(y["geometric"]["count"].as<int>(), 1);
  EXPECT_TRUE(y["geometric"]["dispersion_mm"].IsNull());
}

// The rows by pose and current keep every repetition's error (the Cramer-Rao comparison's input).
TEST_F(SummaryTest, ConditionsGroupTheRepetitionsOfEachPoseAndCurrent) {
  const auto s = Summarize(ReadEstimatesCsv((dir_ / "estimates.csv").string()));
  const MethodSummary& m = s.methods[0];
  ASSERT_EQ(m.conditions.size(), 3u);
  EXPECT_EQ(m.conditions[0].bias_ma, 475.0);
  EXPECT_EQ(m.conditions[0].d_error_mm, (std::vector<double>{10.0, -10.0}));
  EXPECT_EQ(m.conditions[0].theta_error_deg, (std::vector<double>{1.0, -0.5}));
  EXPECT_EQ(m.conditions[1].d_error_mm, (std::vector<double>{20.0, 0.0}));
  EXPECT_EQ(m.conditions[2].d_mm, 1500.0);
  EXPECT_EQ(m.conditions[2].d_error_mm, (std::vector<double>{30.0}));  // the joint row only
  EXPECT_TRUE(s.methods[1].conditions.size() == 1u);  // the failed geometric row is left out
}

// A validation whose recording has no virtual rig: each method's `crb:` says why there is no
// bound; without a recording in the context there is no block at all.
TEST_F(SummaryTest, CrbBlockSaysWhyWithoutAVirtualRig) {
  const auto s = Summarize(ReadEstimatesCsv((dir_ / "estimates.csv").string()));
  const std::string path = (dir_ / "summary.yaml").string();
  const std::map<std::string, std::string> context = {
      {"recording", (dir_ / "no-recording").string()}};
  WriteSummaryYaml(path, s, context, ValidationCrb(context, s));
  YAML::Node y = YAML::LoadFile(path);
  ASSERT_TRUE(y["crb"].IsMap());
  EXPECT_EQ(y["crb"]["source"].as<std::string>().rfind("not computed: ", 0), 0u);
  EXPECT_TRUE(y["geometric"]["crb"].IsMap());
  const std::map<std::string, std::string> no_recording = {{"recipe", "hand-made"}};
  WriteSummaryYaml(path, s, no_recording, ValidationCrb(no_recording, s));
  y = YAML::LoadFile(path);
  EXPECT_FALSE(y["crb"].IsDefined());
}

TEST_F(SummaryTest, RoundTripKeepsEveryRow) {
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

TEST_F(SummaryTest, PositionColumnsRoundTripAndUnknownTruthIsEmpty) {
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

// The health column (calibration health, estimator/health.h) round-trips, files without it read
// as "-", and the default method's summary counts the flagged estimates.
TEST_F(SummaryTest, HealthColumnRoundTripsAndIsCounted) {
  auto rows = ReadEstimatesCsv((dir_ / "estimates.csv").string());
  for (const EstimateRow& r : rows) EXPECT_EQ(r.health, "-");
  rows[0].health = "ok";
  rows[1].health = "blur_larger";
  rows[2].health = "ok";
  const std::string path = (dir_ / "health.csv").string();
  WriteEstimatesCsv(path, rows);
  const auto again = ReadEstimatesCsv(path);
  ASSERT_EQ(again.size(), rows.size());
  EXPECT_EQ(again[1].health, "blur_larger");
  EXPECT_EQ(again[3].health, "-");
  const ValidationSummary summary = Summarize(again);
  const MethodSummary* m = summary.Find("i0_free");
  ASSERT_NE(m, nullptr);
  EXPECT_EQ(m->health_assessed, 3);
  EXPECT_EQ(m->health_flagged, 1);
  const std::string yaml = (dir_ / "summary.yaml").string();
  WriteSummaryYaml(yaml, summary);
  std::ifstream in(yaml);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("health: {assessed: 3, flagged: 1}"), std::string::npos) << text;
}

// estimates.csv as irdist measure writes it, bracket by bracket: every appended row reads back;
// a last line torn by a crash (no end of line) is dropped, and the note names its line.
TEST_F(SummaryTest, StreamedRowsReadBackAndATornLastLineIsDroppedWithANote) {
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
TEST_F(SummaryTest, TimeColumnsRoundTripAndUnknownValuesAreEmpty) {
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

TEST_F(SummaryTest, MotionAndOutsideColumnsRoundTripAndAreCounted) {
  auto rows = ReadEstimatesCsv((dir_ / "estimates.csv").string());
  for (const EstimateRow& r : rows) {
    EXPECT_EQ(r.motion, "-");
    EXPECT_TRUE(r.outside.empty());
  }
  rows[0].motion = "static";
  rows[0].spread_mm = 1.25;
  rows[1].motion = "moving";
  rows[1].spread_mm = 23.5;
  rows[4].outside = {"theta", "t_meas"};
  const std::string path = (dir_ / "motion.csv").string();
  WriteEstimatesCsv(path, rows);
  const auto again = ReadEstimatesCsv(path);
  ASSERT_EQ(again.size(), rows.size());
  EXPECT_EQ(again[1].motion, "moving");
  EXPECT_DOUBLE_EQ(again[1].spread_mm, 23.5);
  EXPECT_TRUE(std::isnan(again[2].spread_mm));
  EXPECT_EQ(again[4].outside, (std::vector<std::string>{"theta", "t_meas"}));
  EXPECT_TRUE(again[5].outside.empty());
  const ValidationSummary summary = Summarize(again);
  const MethodSummary* m = summary.Find("i0_free");
  ASSERT_NE(m, nullptr);
  EXPECT_EQ(m->motion_assessed, 2);
  EXPECT_EQ(m->motion_flagged, 1);
  const std::string yaml = (dir_ / "summary.yaml").string();
  WriteSummaryYaml(yaml, Summarize(again));
  std::ifstream in(yaml);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("motion: {assessed: 2, moving: 1}"), std::string::npos) << text;
}

// estimates.csv is never written through a link planted at its name: the link's target is kept.
TEST_F(SummaryTest, EstimatesCsvIsNeverWrittenThroughALink) {
  const fs::path victim = dir_ / "victim.txt";
  std::ofstream(victim) << "precious\n";
  fs::create_symlink(victim, dir_ / "linked.csv");
  EXPECT_THROW(EstimatesCsvWriter((dir_ / "linked.csv").string()), EstimatesFileError);
  std::ifstream in(victim);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text, "precious\n");
}

TEST_F(SummaryTest, BadRowIsRefusedWithItsLine) {
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

// plan --suggest --from reads best_dt_ms before any probe: a bad value names the file, its line
// and the valid range; a FIFO is refused at once (YAML::LoadFile blocked on it).
TEST_F(SummaryTest, BestDtIsReadStrictlyAndNeverFromAFifo) {
  const fs::path path = dir_ / "summary.yaml";
  std::ofstream(path) << "methods: 2\nbest_dt_ms: 12.5\n";
  EXPECT_EQ(ReadBestDtMs(path.string()), 12.5);
  std::ofstream(path) << "best_dt_ms: null\n";
  EXPECT_EQ(ReadBestDtMs(path.string()), std::nullopt);
  for (const std::string bad : {"-5", "0", ".nan", "1e308", "abc", "[1, 2]"}) {
    SCOPED_TRACE(bad);
    std::ofstream(path) << "i0_free: {}\nbest_dt_ms: " << bad << "\n";
    try {
      ReadBestDtMs(path.string());
      ADD_FAILURE() << "accepted";
    } catch (const EstimatesFileError& e) {
      EXPECT_NE(std::string(e.what()).find(path.string() + ":2:13: best_dt_ms"), std::string::npos)
          << e.what();
      EXPECT_NE(std::string(e.what()).find("(0, 100000]"), std::string::npos) << e.what();
    }
  }
  const fs::path fifo = dir_ / "fifo.yaml";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  try {
    ReadBestDtMs(fifo.string());
    ADD_FAILURE() << "a FIFO was read";
  } catch (const EstimatesFileError& e) {
    EXPECT_NE(std::string(e.what()).find("not a regular file"), std::string::npos) << e.what();
  }
}

TEST(Percentile, InterpolatesBetweenOrderStatistics) {
  EXPECT_EQ(Percentile({}, 50.0), 0.0);
  EXPECT_EQ(Percentile({3.0, 1.0, 2.0}, 50.0), 2.0);
  EXPECT_NEAR(Percentile({0.0, 10.0}, 95.0), 9.5, 1e-12);
  EXPECT_THROW(Percentile({1.0}, 101.0), CheckError);
}

}  // namespace
}  // namespace irdist
