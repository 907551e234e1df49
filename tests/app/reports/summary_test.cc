// summary.yaml (app/reports/summary.h) from the hand-made estimates: its documented keys, the
// bound's block when there is none, the health and motion columns counted from estimates.csv to
// summary.yaml, and best_dt_ms read back strictly (plan --suggest --from).
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
