// The flags of a bracket's rows: the scene's from its frames (the worst figure), the graded
// exposure note, and a reflection or an occluder never reported as motion or focus.
#include "app/processing/estimate_flags.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace irdist {
namespace {

Features Frame() {
  Features f;
  f.blob_found = true;
  f.background = 0.01;
  f.peak = 0.6;
  f.scene.assessed = true;
  return f;
}

CalibratedRanges Table3() {
  CalibratedRanges r;
  r.d_min_mm = 1500.0;
  r.d_max_mm = 3000.0;
  r.theta_max_deg = 35.0;
  r.t_min_ms = 30.0;
  r.t_max_ms = 36.0;
  r.t_ref_min_ms = r.t_ref_max_ms = 8.0;
  return r;
}

EstimateRow Estimated() {
  EstimateRow row;
  row.method = "i0_free";
  row.d_mm = 2000.0;
  row.ok = true;
  return row;
}

std::string Cell(const EstimateRow& row) { return FlagsCell(row.flags); }

TEST(FrameFlags, ACleanBracketHasNone) {
  const Features a = Frame(), b = Frame();
  EXPECT_TRUE(FrameFlags({&a, &b}).flags.empty());
}

TEST(FrameFlags, NameEachCauseWithTheWorstFigureOverTheFrames) {
  Features a = Frame(), b = Frame(), c = Frame();
  a.scene.defect_pixels = 2;
  b.scene.defect_pixels = 5;
  b.scene.second_source = true;
  b.scene.second_source_gap_px = 6.54;
  c.scene.second_source = true;
  c.scene.second_source_gap_px = 9.0;
  c.scene.occluded = true;
  c.scene.occluded_edge_fraction = 0.184;
  c.saturated_pixels = 7;
  EXPECT_EQ(FlagsCell(FrameFlags({&a, &b, &c}).flags),
            "defect_pixels=5 saturated=7 second_source=6.5px occluded=18%");
  Features none;  // no blob
  EXPECT_EQ(FlagsCell(FrameFlags({&a, &none}).flags), "defect_pixels=2 no_blob");
}

TEST(FrameFlags, OtherBlobsMaskedAreANoteUnlessOneIsTooClose) {
  Features a = Frame();
  a.scene.other_blobs = 2;
  const BracketFrameFlags flags = FrameFlags({&a});
  ASSERT_EQ(flags.flags.size(), 1u);
  EXPECT_EQ(flags.flags[0].name, "other_blobs");
  EstimateRow row = Estimated();
  FlagRow(flags, Table3(), {32.0}, nullptr, &row);
  EXPECT_TRUE(row.Trusted());
}

TEST(FlagRow, AnExposureJustBeyondTheCalibrationIsAGradedNote) {
  EstimateRow row = Estimated();
  row.outside = {"t_meas"};
  row.outside_range = true;
  FlagRow({}, Table3(), {30.0, 34.0, 38.0, 40.0}, nullptr, &row);
  EXPECT_EQ(Cell(row), "t_meas_extrapolated=40.0ms");
  EXPECT_TRUE(row.outside.empty());
  EXPECT_FALSE(row.outside_range);
  EXPECT_TRUE(row.Trusted());
  // 45 ms is 25% beyond 36: outside, not graded.
  EstimateRow far = Estimated();
  far.outside = {"theta", "t_meas"};
  FlagRow({}, Table3(), {30.0, 45.0}, nullptr, &far);
  EXPECT_EQ(Cell(far), "outside=theta+t_meas");
  EXPECT_TRUE(far.outside_range);
  EXPECT_FALSE(far.Trusted());
  // Below the range too: 27 ms is 10% below 30.
  EstimateRow low = Estimated();
  low.outside = {"t_meas"};
  FlagRow({}, Table3(), {27.0}, nullptr, &low);
  EXPECT_EQ(Cell(low), "t_meas_extrapolated=27.0ms");
}

HealthCheck BlurLarger() {
  HealthCheck h;
  h.assessed = true;
  h.flagged = true;
  h.blur_var_px2 = 0.9;
  h.calibrated_px2 = 0.6;
  h.sigma_change = 0.30;
  return h;
}

TEST(FlagRow, APeakJustBeyondTheCalibrationsIsAGradedNote) {
  CalibratedRanges ranges = Table3();
  ranges.peak_min = 0.10;
  ranges.peak_max = 0.60;
  Features ref = Frame(), meas = Frame();
  ref.peak = 0.15;
  meas.peak = 0.69;  // 15% above the brightest calibration frame
  EstimateRow row = Estimated();
  row.outside = {"signal"};
  FlagRow(FrameFlags({&ref, &meas}), ranges, {32.0}, nullptr, &row);
  EXPECT_EQ(Cell(row), "signal_extrapolated=+15%");
  EXPECT_FALSE(row.outside_range);
  meas.peak = 0.80;  // 33% above: outside
  EstimateRow far = Estimated();
  far.outside = {"signal"};
  FlagRow(FrameFlags({&ref, &meas}), ranges, {32.0}, nullptr, &far);
  EXPECT_EQ(Cell(far), "outside=signal");
}

TEST(FlagRow, MotionAndFocusCarryTheirFigures) {
  EstimateRow row = Estimated();
  row.motion = "moving";
  row.spread_mm = 23.44;
  const HealthCheck health = BlurLarger();
  FlagRow({}, Table3(), {32.0}, &health, &row);
  EXPECT_EQ(Cell(row), "moving=23.4mm blur_larger=+30%");
}

// A bracket measured through with its own blur: the note `refocused` with the
// blur's change, not the suspect blur_larger; the estimate stays trusted.
TEST(FlagRow, ARefocusedBracketIsANoteWithTheBlursChange) {
  EstimateRow row = Estimated();
  HealthCheck health = BlurLarger();
  health.blob_fit = true;
  health.refocused = true;
  FlagRow({}, Table3(), {32.0}, &health, &row);
  EXPECT_EQ(Cell(row), "refocused=+30%");
  EXPECT_TRUE(row.Trusted());
  ASSERT_NE(FindFlagSpec("refocused"), nullptr);
  EXPECT_FALSE(FindFlagSpec("refocused")->suspect);
}

TEST(FlagRow, AReflectionOrAnOccluderIsNeverCalledMotionOrFocus) {
  const HealthCheck health = BlurLarger();
  for (const char* cause : {"second_source", "occluded"}) {
    EstimateRow row = Estimated();
    row.motion = "moving";
    row.spread_mm = 40.0;
    FlagRow({{{cause, "1"}}}, Table3(), {32.0}, &health, &row);
    ASSERT_EQ(row.flags.size(), 1u) << Cell(row);
    EXPECT_EQ(row.flags[0].name, cause);
    EXPECT_EQ(row.motion, "moving");  // the column keeps its assessment
  }
}

TEST(FlagRow, ARowWithoutAnEstimateSaysSo) {
  EstimateRow row = Estimated();
  row.ok = false;
  FlagRow({{{"no_blob", ""}}}, Table3(), {32.0}, nullptr, &row);
  EXPECT_EQ(Cell(row), "no_blob no_estimate");
}

}  // namespace
}  // namespace irdist
