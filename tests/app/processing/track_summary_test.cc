#include "app/processing/track_summary.h"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <vector>


namespace irdist {
namespace {

// Frames every 20 ms of a slide cruising at 500 mm/s from 1500 mm (cruise from frame 0), each
// estimate off the truth by +-error_mm alternately, the filter's velocity `v` with se 10.
struct Track {
  std::vector<TrackFrameRow> rows;
  std::vector<TrackTruth> truths;
};

Track Cruise(int frames, double error_mm, double v, double bound_mm) {
  Track t;
  for (int i = 0; i < frames; ++i) {
    TrackFrameRow r;
    r.frame = i;
    r.segment = 0;
    r.ok = true;
    const double truth = 1500.0 + 500.0 * 0.02 * i;
    r.d_mm = truth + (i % 2 == 0 ? error_mm : -error_mm);
    r.d_se_mm = 3.0;
    r.filtered = true;
    r.v_mm_per_s = v;
    r.v_se_mm_per_s = 10.0;
    t.rows.push_back(r);
    TrackTruth truth_of;
    truth_of.known = true;
    truth_of.d_mm = truth;
    truth_of.v_mm_per_s = 500.0;
    truth_of.cruise_s = 0.02 * i;
    truth_of.bound_mm = bound_mm;
    t.truths.push_back(truth_of);
  }
  return t;
}

TEST(TrackSummaryTest, ErrorsAgainstTheTruthAndTheBoundOverTheMovingFrames) {
  Track t = Cruise(100, 2.0, 505.0, 2.0);
  t.rows[3].ok = false;  // a frame without an estimate: counted, not scored
  t.truths[7].v_mm_per_s = 0.0;  // a frame at rest: not a moving one
  const TrackSummary s = SummarizeTrack(t.rows, t.truths, 0.5);
  EXPECT_EQ(s.frames, 100);
  EXPECT_EQ(s.estimated, 99);
  EXPECT_EQ(s.with_truth, 100);
  EXPECT_EQ(s.moving, 98);
  EXPECT_NEAR(s.error_rms_mm, 2.0, 1e-9);
  EXPECT_NEAR(s.bound_rms_mm, 2.0, 1e-9);
  EXPECT_NEAR(s.ratio_to_bound, 1.0, 1e-9);
  EXPECT_NEAR(s.se_rms_mm, 3.0, 1e-9);
  EXPECT_NEAR(s.velocity_error_rms_mm_per_s, 5.0, 1e-9);
  ASSERT_EQ(s.cruises.size(), 1u);
  EXPECT_EQ(s.cruises[0].frames, 75);  // from 0.5 s in: frames 25..99
  EXPECT_NEAR(s.cruises[0].z_mean, 0.5, 1e-9);
  EXPECT_NEAR(s.cruises[0].z_last, 0.5, 1e-9);
  EXPECT_TRUE(s.cruises[0].within_3se);
}

TEST(TrackSummaryTest, AVelocityOutsideThreeStandardErrorsAndAnErrorOverTheGoalAreSaid) {
  const Track t = Cruise(60, 4.0, 540.0, 2.0);
  const TrackSummary s = SummarizeTrack(t.rows, t.truths, 0.5);
  EXPECT_NEAR(s.ratio_to_bound, 2.0, 1e-9);
  ASSERT_EQ(s.cruises.size(), 1u);
  EXPECT_FALSE(s.cruises[0].within_3se);  // 40 mm/s off at se 10: z 4
  const YAML::Node y = YAML::Load(TrackSummaryYaml(s, {{{"recipe", "r.yaml"}}, {{"lost", 0}}, true}));
  EXPECT_EQ(y["kind"].as<std::string>(), "track");
  EXPECT_TRUE(y["cut"].as<bool>());
  EXPECT_EQ(y["recipe"].as<std::string>(), "r.yaml");
  EXPECT_EQ(y["frames"]["lost"].as<int>(), 0);
  EXPECT_FALSE(y["distance_error_moving"]["within_goal"].as<bool>());
  EXPECT_NEAR(y["distance_error_moving"]["rms_mm"].as<double>(), 4.0, 1e-6);
  EXPECT_FALSE(y["velocity"]["velocity_on_cruise"][0]["within_3se"].as<bool>());
}

TEST(TrackSummaryTest, TheCsvRowHoldsEveryColumnOfItsHeader) {
  TrackFrameRow r;
  r.frame = 12;
  r.utc_ns = 1700000000000000000;
  r.ok = true;
  r.d_mm = 2000.5;
  r.flags = "saturated,clipped";  // one cell
  const auto columns = [](const std::string& line) {
    return std::count(line.begin(), line.end(), ',') + 1;
  };
  EXPECT_EQ(columns(TrackCsvRow(r)), columns(TrackCsvHeader()));
  EXPECT_EQ(TrackCsvRow(r).rfind("12,0,,2023-11-14T22:13:20", 0), 0u) << TrackCsvRow(r);
  EXPECT_NE(TrackCsvRow(r).find("saturated clipped"), std::string::npos);
}

}  // namespace
}  // namespace irdist
