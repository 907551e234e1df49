#include "app/runs/suggest.h"

#include <gtest/gtest.h>

#include <cmath>

namespace irdist {
namespace {

// A linear camera: background 0.02, the nearest pose gains 0.025/ms, the farthest 0.012/ms.
std::vector<ProbeFrame> Probes() {
  std::vector<ProbeFrame> p;
  for (double t : {5.0, 10.0}) {
    p.push_back({true, t, 525.0, 0.02 + 0.025 * t, 0.02});
    p.push_back({false, t, 475.0, 0.02 + 0.012 * t, 0.02});
  }
  return p;
}

TEST(SuggestOptions, DefaultsAreValid) {
  std::string why;
  EXPECT_TRUE(SuggestOptions().IsValid(&why)) << why;
}

// A best dt no exposure can hold (summary.yaml's best_dt_ms 1e308, nan, -5) is invalid: RunSuggest
// checks the options before the probe sweep.
TEST(SuggestOptions, BestDtOutsideAnyExposureIsInvalid) {
  SuggestOptions o;
  std::string why;
  for (double bad : {-5.0, 0.0, std::nan(""), 1e308, 100000.5}) {
    o.best_dt_ms = bad;
    EXPECT_FALSE(o.IsValid(&why)) << bad;
    EXPECT_NE(why.find("(0, 100000] ms"), std::string::npos) << why;
  }
  o.best_dt_ms = 100000.0;
  EXPECT_TRUE(o.IsValid(&why)) << why;
}

TEST(Suggest, LongestExposureKeepsTheNearestPoseBelowTheLimit) {
  const Suggestion s = SuggestExposures(Probes(), SuggestOptions());
  ASSERT_TRUE(s.feasible) << s.reason;
  // 0.02 + 0.025 t <= 0.85 -> t <= 33.2 ms -> 33.0 on the 0.5 ms grid.
  ASSERT_EQ(s.t_meas_ms.size(), 4u);
  EXPECT_DOUBLE_EQ(s.t_meas_ms.back(), 33.0);
  EXPECT_DOUBLE_EQ(s.t_meas_ms.front(), 27.0);
  // 0.012 t >= 0.08 -> t >= 6.67 ms -> 7.0.
  EXPECT_DOUBLE_EQ(s.t_ref_ms, 7.0);
  EXPECT_LE(s.nearest_peak_at_longest, 0.85 + 1e-12);
  EXPECT_GE(s.farthest_signal_at_ref, 0.08 - 1e-12);
  EXPECT_DOUBLE_EQ(s.bias_ma, 525.0);
}

TEST(Suggest, BestDtFromAValidationCentresTheMeasurementExposures) {
  SuggestOptions o;
  o.best_dt_ms = 16.0;
  const Suggestion s = SuggestExposures(Probes(), o);
  ASSERT_TRUE(s.feasible);
  // t_r 7 + dt 16 = 23, +-3 ms: 20, 22, 24, 26.
  EXPECT_EQ(s.t_meas_ms, (std::vector<double>{20.0, 22.0, 24.0, 26.0}));
  o.best_dt_ms = 40.0;  // would saturate: falls back to the longest safe exposure
  EXPECT_DOUBLE_EQ(SuggestExposures(Probes(), o).t_meas_ms.back(), 33.0);
}

TEST(Suggest, TooWideARangeIsInfeasibleAndSaysWhatToChange) {
  std::vector<ProbeFrame> p = Probes();
  for (ProbeFrame& f : p) {
    if (!f.nearest) f.peak = 0.02 + 0.0012 * f.exposure_ms;  // ten times fainter far end
  }
  const Suggestion s = SuggestExposures(p, SuggestOptions());
  EXPECT_FALSE(s.feasible);
  EXPECT_NE(s.reason.find("narrow the recipe"), std::string::npos) << s.reason;
  EXPECT_NE(s.BriefReport().find("no feasible exposures"), std::string::npos);
}

TEST(Suggest, NeedsTwoExposuresAtEachEnd) {
  std::vector<ProbeFrame> p = Probes();
  p.erase(p.begin() + 1);  // the far end keeps one probe
  EXPECT_THROW(SuggestExposures(p, SuggestOptions()), CheckError);
}

}  // namespace
}  // namespace irdist
