// What measure --track shows (app/live/track_output.h): the track line's JSON, a bracket's check
// against the track (the track's distance carried over the gap by its velocity), and the summary's
// latency quantiles and rate.
#include "app/live/track_output.h"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <string>

namespace irdist {
namespace {

// The track at t = 10 s: 2000 +- 3 mm moving at 100 +- 4 mm/s.
TrackState Track() {
  TrackState s;
  s.time_s = 10.0;
  s.position_mm = {2000.0};
  s.position_sd_mm = {3.0};
  s.velocity_mm_per_s = {100.0};
  s.velocity_sd_mm_per_s = {4.0};
  return s;
}

MeasureSample Bracket(double d_mm, double se_mm) {
  MeasureSample b;
  b.have_estimate = true;
  b.estimate.ok = true;
  b.estimate.d_mm = d_mm;
  b.estimate.d_std_mm = se_mm;
  return b;
}

// 1 s later the track is at 2100 mm with se sqrt(3^2 + 4^2) = 5 mm; a bracket at 2112 +- 12 mm
// lies (12 / 13) combined standard errors away: it agrees; one at 2200 mm does not.
TEST(CheckAgainstTrack, CarriesTheTrackOverTheGapAndJudgesInCombinedErrors) {
  const TrackCheck near = CheckAgainstTrack(Track(), true, 11.0, Bracket(2112.0, 12.0));
  ASSERT_TRUE(near.assessed);
  EXPECT_DOUBLE_EQ(near.track_d_mm, 2100.0);
  EXPECT_DOUBLE_EQ(near.track_se_mm, 5.0);
  EXPECT_NEAR(near.z, 12.0 / 13.0, 1e-12);
  EXPECT_TRUE(near.agree);
  const TrackCheck far = CheckAgainstTrack(Track(), true, 11.0, Bracket(2200.0, 12.0));
  EXPECT_NEAR(far.z, 100.0 / 13.0, 1e-12);
  EXPECT_FALSE(far.agree);
  // A bracket stamped before the track's last frame is compared at the track's time.
  EXPECT_DOUBLE_EQ(CheckAgainstTrack(Track(), true, 9.0, Bracket(2000.0, 4.0)).track_d_mm, 2000.0);
}

TEST(CheckAgainstTrack, NotAssessedWithoutATrackOrABracketEstimate) {
  EXPECT_FALSE(CheckAgainstTrack(Track(), false, 11.0, Bracket(2100.0, 5.0)).assessed);
  EXPECT_FALSE(CheckAgainstTrack(TrackState(), true, 11.0, Bracket(2100.0, 5.0)).assessed);
  MeasureSample failed = Bracket(2100.0, 5.0);
  failed.estimate.ok = false;
  EXPECT_FALSE(CheckAgainstTrack(Track(), true, 11.0, failed).assessed);
  const TrackCheck no_se = CheckAgainstTrack(Track(), true, 11.0, Bracket(2500.0, 0.0));
  EXPECT_FALSE(no_se.assessed);
  EXPECT_TRUE(no_se.agree);  // nothing to disagree with
}

TEST(TrackStats, NoLatencyWithoutLines) {
  const TrackStats stats;
  EXPECT_EQ(stats.lines(), 0);
  EXPECT_TRUE(std::isnan(stats.LatencyQuantileMs(0.5)));
}

TrackSample TrackedFrame() {
  TrackSample s;
  s.estimate.mode = "track";
  s.estimate.bracket = 41;
  s.estimate.have_estimate = true;
  s.estimate.estimate.ok = true;
  s.estimate.estimate.d_mm = 2000.5;
  s.estimate.estimate.d_std_mm = 2.5;
  s.acquisition = "triggered";
  s.frame = 41;
  s.camera_frame_id = 42;
  s.exposure_ms = 8.0;
  s.filtered = true;
  s.filter.position_mm = {2000.25};
  s.filter.position_sd_mm = {0.75};
  s.filter.velocity_mm_per_s = {-1.5};
  s.filter.velocity_sd_mm_per_s = {4.0};
  s.filter.used = true;
  s.filter.frames = 12;
  s.counters.received = 50;
  s.counters.skipped = 8;
  return s;
}

TEST(TrackJson, MeasuresSchemaWithTheModeTheFilterAndTheCounters) {
  const YAML::Node j = YAML::Load(TrackJson(TrackedFrame()));
  EXPECT_EQ(j["schema"].as<std::string>(), "irdist.measure/2");
  EXPECT_EQ(j["mode"].as<std::string>(), "track");
  EXPECT_EQ(j["acquisition"].as<std::string>(), "triggered");
  EXPECT_EQ(j["frame"].as<int>(), 41);
  EXPECT_EQ(j["camera_frame_id"].as<int>(), 42);
  EXPECT_DOUBLE_EQ(j["d_mm"].as<double>(), 2000.5);
  EXPECT_DOUBLE_EQ(j["d_se_mm"].as<double>(), 2.5);
  EXPECT_DOUBLE_EQ(j["track"]["d_mm"].as<double>(), 2000.25);
  EXPECT_DOUBLE_EQ(j["track"]["d_se_mm"].as<double>(), 0.75);
  EXPECT_DOUBLE_EQ(j["track"]["v_mm_per_s"].as<double>(), -1.5);
  EXPECT_DOUBLE_EQ(j["track"]["v_se_mm_per_s"].as<double>(), 4.0);
  EXPECT_EQ(j["track"]["frames"].as<int>(), 12);
  EXPECT_EQ(j["counters"]["skipped"].as<int>(), 8);
  EXPECT_TRUE(j["check"].IsNull());
}

TEST(TrackJson, ABracketLineHasNoFrameAndCarriesItsCheck) {
  TrackSample s = TrackedFrame();
  s.estimate.mode = "bracket";
  s.frame = -1;
  s.filtered = false;
  s.check.assessed = true;
  s.check.track_d_mm = 2001.0;
  s.check.z = -0.5;
  const YAML::Node j = YAML::Load(TrackJson(s));
  EXPECT_EQ(j["mode"].as<std::string>(), "bracket");
  EXPECT_TRUE(j["frame"].IsNull());
  EXPECT_TRUE(j["track"].IsNull());
  EXPECT_DOUBLE_EQ(j["check"]["track_d_mm"].as<double>(), 2001.0);
  EXPECT_TRUE(j["check"]["agree"].as<bool>());
}

// The track's distance is carried to the bracket's time by its velocity; the se adds the
// velocity's over the gap.
TEST(CheckAgainstTrack, CarriesTheTrackToTheBracketAndComparesInStandardErrors) {
  TrackState last;
  last.time_s = 10.0;
  last.position_mm = {2000.0};
  last.position_sd_mm = {3.0};
  last.velocity_mm_per_s = {100.0};
  last.velocity_sd_mm_per_s = {20.0};
  MeasureSample bracket;
  bracket.have_estimate = true;
  bracket.estimate.ok = true;
  bracket.estimate.d_mm = 2020.0;
  bracket.estimate.d_std_mm = 4.0;
  TrackCheck c = CheckAgainstTrack(last, true, 10.2, bracket);
  ASSERT_TRUE(c.assessed);
  EXPECT_NEAR(c.track_d_mm, 2020.0, 1e-9);
  EXPECT_NEAR(c.track_se_mm, 5.0, 1e-9);  // sqrt(3^2 + (20 x 0.2)^2)
  EXPECT_NEAR(c.z, 0.0, 1e-9);
  EXPECT_TRUE(c.agree);
  bracket.estimate.d_mm = 2020.0 + 4.0 * std::sqrt(41.0);  // 4 combined se away
  c = CheckAgainstTrack(last, true, 10.2, bracket);
  EXPECT_NEAR(c.z, 4.0, 1e-9);
  EXPECT_FALSE(c.agree);
  EXPECT_FALSE(CheckAgainstTrack(last, false, 10.2, bracket).assessed);  // no track yet
}

TEST(TrackStats, LatencyQuantilesAndTheRatioOfEstimatesToFrames) {
  TrackStats stats;
  for (int i = 1; i <= 100; ++i) {
    TrackSample s = TrackedFrame();
    s.estimate.latency_ms = 0.1 * i;  // 0.1 .. 10 ms
    stats.Add(s);
  }
  EXPECT_NEAR(stats.LatencyQuantileMs(0.5), 5.0, 0.011);
  EXPECT_NEAR(stats.LatencyQuantileMs(0.95), 9.5, 0.011);
  TrackCounters c;
  c.received = 200;
  const std::string report = stats.Report(2.0, c);
  EXPECT_NE(report.find("Tracked 100 frames in 2.00 s (50.00 estimates/s; the camera delivered "
                        "100.00 frames/s: ratio 0.500)"),
            std::string::npos)
      << report;
  EXPECT_NE(report.find(", max 10.00 ms"), std::string::npos) << report;
}

}  // namespace
}  // namespace irdist
