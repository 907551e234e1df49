// measure's output forms: the JSON object of docs/measure.md (parsed back), the text line, the
// quality flags and the summary's statistics. The live command is tested end to end in
// tests/integration/measure_test.cc.
#include "app/live/measure.h"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <sstream>

#include "app/inputs/errors.h"
#include "app/runs/resume.h"

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
  EXPECT_EQ(j["schema"].as<std::string>(), "irdist.measure/2");
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

// The bracket's absolute time: UTC (ISO 8601, microseconds) beside the monotonic clock and the
// camera's timestamp (all 64 bits); unknown ones are null.
TEST(MeasureJson, CarriesTheBracketsUtcTimeBesideTheMonotonicAndCameraClocks) {
  MeasureSample s = Good();
  s.utc_ns = 1796191923123456789;  // 2026-12-02T06:12:03.123456789Z
  s.host_monotonic_ns = 987654321012345;
  s.camera_timestamp_ns = 18446744073709551000ull;
  YAML::Node j = YAML::Load(MeasureJson(s));
  EXPECT_EQ(j["utc_time"].as<std::string>(), "2026-12-02T06:12:03.123456Z");
  EXPECT_EQ(j["host_monotonic_ns"].as<std::int64_t>(), 987654321012345);
  EXPECT_EQ(j["camera_timestamp_ns"].as<std::uint64_t>(), 18446744073709551000ull);
  s.utc_ns = 0;
  s.camera_timestamp_ns = 0;  // a camera without timestamps
  j = YAML::Load(MeasureJson(s));
  EXPECT_TRUE(j["utc_time"].IsNull());
  EXPECT_TRUE(j["camera_timestamp_ns"].IsNull());
}

TEST(QualityFlags, NamesEachProblem) {
  EXPECT_EQ(QualityFlags(Good()), "ok");
  MeasureSample s = Good();
  s.saturated = true;
  s.estimate.outside_range = true;
  s.estimate.outside = {"theta", "t_meas"};
  EXPECT_EQ(QualityFlags(s), "saturated,outside_range(theta t_meas)");
}

HealthCheck BlurLarger() {
  HealthCheck h;
  h.assessed = true;
  h.frames = 4;
  h.blur_var_px2 = 0.91;
  h.calibrated_px2 = 0.57;
  h.sigma_change = 0.30;
  h.z = 40.0;
  h.flagged = true;
  return h;
}

MotionCheck Moving() {
  MotionCheck m;
  m.assessed = true;
  m.exposures = 4;
  m.chi2 = 900.0;
  m.chi2_limit = 16.27;
  m.spread_mm = 23.4;
  m.moving = true;
  return m;
}

// Health and motion in every output form: the live line's flags, the JSON's flags and the figures
// behind them, the summary's counts.
TEST(QualityFlags, NameHealthAndMotionWithTheirFigures) {
  MeasureSample s = Good();
  s.health = BlurLarger();
  s.motion = Moving();
  EXPECT_EQ(QualityFlags(s), "blur_larger(+30%),moving(23.4 mm)");
  EXPECT_NE(MeasureLine(s).find("[blur_larger(+30%),moving(23.4 mm)]"), std::string::npos);
}

TEST(MeasureJson, CarriesHealthMotionAndTheRangesOutside) {
  MeasureSample s = Good();
  YAML::Node j = YAML::Load(MeasureJson(s));
  EXPECT_FALSE(j["flags"]["unhealthy"].as<bool>());
  EXPECT_FALSE(j["flags"]["moving"].as<bool>());
  EXPECT_EQ(j["outside"].size(), 0u);
  EXPECT_TRUE(j["health"].IsNull());  // not assessed
  EXPECT_TRUE(j["motion"].IsNull());
  s.health = BlurLarger();
  s.motion = Moving();
  s.estimate.outside_range = true;
  s.estimate.outside = {"theta"};
  j = YAML::Load(MeasureJson(s));
  EXPECT_TRUE(j["flags"]["unhealthy"].as<bool>());
  EXPECT_TRUE(j["flags"]["moving"].as<bool>());
  EXPECT_TRUE(j["flags"]["outside_range"].as<bool>());
  ASSERT_EQ(j["outside"].size(), 1u);
  EXPECT_EQ(j["outside"][0].as<std::string>(), "theta");
  EXPECT_EQ(j["health"]["status"].as<std::string>(), "blur_larger");
  EXPECT_DOUBLE_EQ(j["health"]["blur_var_px2"].as<double>(), 0.91);
  EXPECT_DOUBLE_EQ(j["health"]["calibrated_blur_var_px2"].as<double>(), 0.57);
  EXPECT_DOUBLE_EQ(j["health"]["sigma_change"].as<double>(), 0.30);
  EXPECT_DOUBLE_EQ(j["motion"]["spread_mm"].as<double>(), 23.4);
  EXPECT_DOUBLE_EQ(j["motion"]["chi2_limit"].as<double>(), 16.27);
  EXPECT_EQ(j["motion"]["exposures"].as<int>(), 4);
}

TEST(MeasureStats, CountsUnhealthyMovingAndOutsideBrackets) {
  MeasureStats stats;
  MeasureSample healthy = Good();
  healthy.health = BlurLarger();
  healthy.health.flagged = false;
  stats.Add(healthy);
  MeasureSample bad = Good();
  bad.health = BlurLarger();
  bad.motion = Moving();
  bad.estimate.outside_range = true;
  bad.estimate.outside = {"theta", "t_meas"};
  stats.Add(bad);
  const std::string report = stats.Report(1.0);
  EXPECT_NE(report.find("health: 1 of 2 assessed brackets unhealthy"), std::string::npos) << report;
  EXPECT_NE(report.find("motion: 1 of 1 assessed brackets moving"), std::string::npos) << report;
  EXPECT_NE(report.find("outside the calibrated ranges: 1 (t_meas 1, theta 1)"), std::string::npos)
      << report;
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

// Two `measure --out` on one folder at once: the second is refused by the folder's lock (the
// first's estimates would be lost), before anything else is opened.
TEST(MeasureOut, ASecondMeasurementOnALiveFolderIsRefused) {
  namespace fs = std::filesystem;
  const std::string dir =
      (fs::temp_directory_path() / ("irdist-measure-lock-" + std::to_string(::getpid()))).string();
  fs::remove_all(dir);
  const RunFolderLock first(dir, "measure");
  MeasureArgs args;
  args.model = dir + "/no-model.yaml";
  args.out_dir = dir;
  std::ostringstream out, err;
  try {
    RunMeasure(args, {out, err});
    FAIL() << "a second measure on a live folder";
  } catch (const RunFolderError& e) {
    EXPECT_NE(std::string(e.what()).find("irdist measure, process " + std::to_string(::getpid())),
              std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace irdist
