#include "app/processing/track_truth.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "sim/motion_profile.h"
#include "sim/trajectory_file.h"

namespace irdist {
namespace {

// The virtual rig's truth: a trajectory file with the slide at rest at 1500 mm from 0 s, then
// cruising 1500 -> 3000 mm at 500 mm/s from 1 s (2 m/s^2); pan and tilt at rest at 0. A frame's
// truth is its pose at the middle of its exposure on the trajectory's clock, its bound the
// one-frame Cramer-Rao bound of recipes/rigs/virtual.yaml's physics.
TEST(TrackTruthTest, TheVirtualRigsTruthIsTheTrajectoryAtMidExposureWithTheOneFrameBound) {
  const std::string dir = std::string(IRDIST_BINARY_DIR) + "/tests/app/track_truth";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string csv = dir + "/trajectory.csv";
  {
    sim::TrajectoryLog log(csv, [](double t_s) { return static_cast<std::int64_t>(t_s * 1e9); });
    log.Append(sim::RigAxis::kSlide, sim::MotionProfile::Rest(1500.0, 0.0));
    log.Append(sim::RigAxis::kPan, sim::MotionProfile::Rest(0.0, 0.0));
    log.Append(sim::RigAxis::kTilt, sim::MotionProfile::Rest(0.0, 0.0));
    log.Append(sim::RigAxis::kSlide,
               sim::MotionProfile::Make(1500.0, 3000.0, 1.0, 0.0, 500.0, 2000.0));
    ASSERT_EQ(log.Error(), "");
  }
  std::vector<TrackFrameRow> rows(3);
  // Exposures starting at 0.5 s (at rest), 2.0 s and 2.5 s (cruising: 0.25 s accelerating,
  // 62.5 mm, then 500 mm/s), each 8 ms: their middles 4 ms later.
  const double starts_s[] = {0.5, 2.0, 2.5};
  for (std::size_t i = 0; i < rows.size(); ++i) {
    rows[i].camera_timestamp_ns = static_cast<std::uint64_t>(std::llround(starts_s[i] * 1e9));
    rows[i].exposure_ms = 8.0;
  }
  const std::vector<TrackTruth> t = VirtualTrackTruths(
      rows, csv, std::string(IRDIST_SOURCE_DIR) + "/recipes/rigs/virtual.yaml", 490.0);
  ASSERT_EQ(t.size(), 3u);
  EXPECT_TRUE(t[0].known);
  EXPECT_NEAR(t[0].d_mm, 1500.0, 1e-9);
  EXPECT_DOUBLE_EQ(t[0].v_mm_per_s, 0.0);
  EXPECT_TRUE(std::isnan(t[0].cruise_s));
  EXPECT_NEAR(t[1].d_mm, 1500.0 + 62.5 + 500.0 * (2.004 - 1.25), 1e-6);
  EXPECT_NEAR(t[1].v_mm_per_s, 500.0, 1e-9);
  EXPECT_NEAR(t[1].cruise_s, 2.004 - 1.25, 1e-9);
  EXPECT_DOUBLE_EQ(t[1].sd_mm, 0.0);
  // The bound grows with the distance and lies in the millimetres at 1.5-3 m (one 8 ms frame).
  EXPECT_GT(t[0].bound_mm, 0.5);
  EXPECT_LT(t[0].bound_mm, 10.0);
  EXPECT_GT(t[2].bound_mm, t[0].bound_mm);
}

// A real rig's truth: the commanded trapezoid from when the move was sent, the frame's middle of
// exposure its arrival less the readout and half the exposure.
TEST(TrackTruthTest, TheCommandedProfileIsTheTruthOnARealRig) {
  std::vector<TrackFrameRow> rows(3);
  for (TrackFrameRow& r : rows) {
    r.exposure_ms = 8.0;
    r.d_se_mm = 1.5;
  }
  const std::int64_t start_ns = 10'000'000'000;
  // Mid-exposure 1 s, 2 s and 9 s after the start (readout 2 ms, half exposure 4 ms).
  const std::vector<std::int64_t> arrival = {start_ns + 1'006'000'000, start_ns + 2'006'000'000,
                                             start_ns + 9'006'000'000};
  const std::vector<TrackTruth> truths = CommandedTrackTruths(
      rows, arrival, {{1000.0, 3000.0, 500.0, 1000.0, start_ns}}, 2.0, 2.5);
  // 0.5 s accelerating (125 mm), then cruising: at 1 s 125 + 250 mm, at 2 s 125 + 750 mm.
  EXPECT_NEAR(truths[0].d_mm, 1375.0, 1e-6);
  EXPECT_NEAR(truths[0].v_mm_per_s, 500.0, 1e-6);
  EXPECT_NEAR(truths[0].cruise_s, 0.5, 1e-6);
  EXPECT_NEAR(truths[1].d_mm, 1875.0, 1e-6);
  EXPECT_DOUBLE_EQ(truths[0].sd_mm, 2.5);
  EXPECT_DOUBLE_EQ(truths[0].bound_mm, 1.5);
  EXPECT_NEAR(truths[2].d_mm, 3000.0, 1e-6);  // arrived and standing
  EXPECT_DOUBLE_EQ(truths[2].v_mm_per_s, 0.0);
}

}  // namespace
}  // namespace irdist
