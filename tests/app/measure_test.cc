// measure's output forms: the JSON object of docs/measure.md (parsed back), the text line, the
// quality flags and the summary's statistics. The live command is tested end to end in
// tests/integration/measure_test.cc.
#include "app/measure.h"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>

namespace irdist {
namespace {

MeasureSample Good() {
  MeasureSample s;
  s.bracket = 7;
  s.time_s = 1.5;
  s.latency_ms = 0.75;
  s.have_estimate = true;
  s.estimate.ok = true;
  s.estimate.d_mm = 2001.25;
  s.estimate.d_std_mm = 3.5;
  s.estimate.theta_deg = 12.5;
  s.estimate.theta_std_deg = 0.25;
  s.blob_found = true;
  s.blob_x_px = 640.25;
  s.blob_y_px = 511.75;
  return s;
}

// Good() with a 3D position (a rig with intrinsics).
MeasureSample GoodWithPosition() {
  MeasureSample s = Good();
  s.has_position = true;
  s.x_mm = 10.0;
  s.y_mm = -5.0;
  s.z_mm = 2001.0;
  return s;
}

TEST(MeasureJson, ParsesWithEveryDocumentedField) {
  const MeasureSample s = GoodWithPosition();
  const YAML::Node j = YAML::Load(MeasureJson(s));
  EXPECT_EQ(j["schema"].as<std::string>(), "irdist.measure/1");
  EXPECT_EQ(j["bracket"].as<int>(), 7);
  EXPECT_TRUE(j["ok"].as<bool>());
  EXPECT_DOUBLE_EQ(j["d_mm"].as<double>(), 2001.25);
  EXPECT_DOUBLE_EQ(j["d_se_mm"].as<double>(), 3.5);
  EXPECT_DOUBLE_EQ(j["theta_deg"].as<double>(), 12.5);
  EXPECT_DOUBLE_EQ(j["theta_se_deg"].as<double>(), 0.25);
  EXPECT_DOUBLE_EQ(j["blob_x_px"].as<double>(), 640.25);
  EXPECT_DOUBLE_EQ(j["latency_ms"].as<double>(), 0.75);
  EXPECT_FALSE(j["flags"]["saturated"].as<bool>());
  EXPECT_DOUBLE_EQ(j["position"]["x_mm"].as<double>(), 10.0);
  EXPECT_DOUBLE_EQ(j["position"]["z_mm"].as<double>(), 2001.0);
}

TEST(MeasureJson, NoEstimateGivesNullsAndNoPosition) {
  MeasureSample s = Good();
  s.estimate.ok = false;
  s.blob_found = false;
  const YAML::Node j = YAML::Load(MeasureJson(s));
  EXPECT_FALSE(j["ok"].as<bool>());
  EXPECT_TRUE(j["d_mm"].IsNull());
  EXPECT_TRUE(j["blob_x_px"].IsNull());
  EXPECT_TRUE(j["position"].IsNull());
  EXPECT_TRUE(j["flags"]["no_blob"].as<bool>());
}

TEST(QualityFlags, NamesEachProblem) {
  EXPECT_EQ(QualityFlags(Good()), "ok");
  MeasureSample s = Good();
  s.saturated = true;
  s.estimate.outside_range = true;
  EXPECT_EQ(QualityFlags(s), "saturated,outside_range");
}

TEST(MeasureLine, ShowsDistanceThetaAndFlags) {
  const std::string line = MeasureLine(Good());
  EXPECT_NE(line.find("#7"), std::string::npos) << line;
  EXPECT_NE(line.find("2001.2"), std::string::npos) << line;
  EXPECT_NE(line.find("[ok]"), std::string::npos) << line;
}

// The live line fits an 80-column terminal (one column spare, so it never wraps and leaves no
// trail), keeping the distance and the flags; a wide terminal gets the whole line.
TEST(MeasureLine, FitsTheTerminalsWidthKeepingDistanceAndFlags) {
  MeasureSample s = GoodWithPosition();
  s.saturated = true;
  ASSERT_GT(MeasureLine(s).size(), 80u);  // the whole line does not fit 80 columns
  for (std::size_t width : {80u, 60u, 40u}) {
    const std::string line = MeasureLine(s, width);
    EXPECT_LT(line.size(), width) << line;
    EXPECT_NE(line.find("d 2001.2"), std::string::npos) << line;
    EXPECT_NE(line.find("[saturated]"), std::string::npos) << line;
  }
  EXPECT_EQ(MeasureLine(s, 300), MeasureLine(s));
  EXPECT_EQ(TerminalWidthChars(-1), 80u);  // not a terminal
}

TEST(MeasureStats, MeanAndSdOverTheEstimates) {
  MeasureStats stats;
  for (double d : {1990.0, 2000.0, 2010.0}) {
    MeasureSample s = Good();
    s.estimate.d_mm = d;
    stats.Add(s);
  }
  MeasureSample failed = Good();
  failed.estimate.ok = false;
  stats.Add(failed);
  EXPECT_EQ(stats.count(), 4);
  const std::string report = stats.Report(2.0);
  EXPECT_NE(report.find("Measured 4 brackets"), std::string::npos) << report;
  EXPECT_NE(report.find("2.00 brackets/s"), std::string::npos) << report;
  EXPECT_NE(report.find("3 with an estimate"), std::string::npos) << report;
  EXPECT_NE(report.find("d: mean 2000.00 mm, sd 10.00 mm"), std::string::npos) << report;
}

}  // namespace
}  // namespace irdist
