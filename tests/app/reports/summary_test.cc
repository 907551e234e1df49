#include "app/reports/summary.h"

#include "app/processing/crb.h"
#include "tests/app/processing/hand_made_estimates.h"

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

// One line of a text file, for istream_iterator.
struct Line : std::string {
  friend std::istream& operator>>(std::istream& in, Line& line) { return std::getline(in, line); }
};


TEST_F(HandMadeEstimatesTest, SummaryYamlHasTheDocumentedKeys) {
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

// A validation whose recording has no virtual rig: each method's `crb:` says why there is no
// bound; without a recording in the context there is no block at all.
TEST_F(HandMadeEstimatesTest, CrbBlockSaysWhyWithoutAVirtualRig) {
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

// The health column (calibration health, estimator/health.h) round-trips, files without it read
// as "-", and the default method's summary counts the flagged estimates.
TEST_F(HandMadeEstimatesTest, HealthColumnRoundTripsAndIsCounted) {
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

TEST_F(HandMadeEstimatesTest, MotionAndOutsideColumnsRoundTripAndAreCounted) {
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

// plan --suggest --from reads best_dt_ms before any probe: a bad value names the file, its line
// and the valid range; a FIFO is refused at once (YAML::LoadFile blocked on it).
TEST_F(HandMadeEstimatesTest, BestDtIsReadStrictlyAndNeverFromAFifo) {
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

}  // namespace
}  // namespace irdist
