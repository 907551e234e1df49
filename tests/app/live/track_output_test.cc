// What measure --track shows (app/live/track_output.h): a bracket's check against the track, the
// track's distance carried over the gap by its velocity, and the summary's latency quantile.
#include "app/live/track_output.h"

#include <gtest/gtest.h>

#include <cmath>

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

}  // namespace
}  // namespace irdist
