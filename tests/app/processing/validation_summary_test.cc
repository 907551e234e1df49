// The validation's statistics (app/processing/validation_summary.h) on the hand-made rows, each
// figure computed by hand.
#include "app/processing/validation_summary.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "tests/app/processing/hand_made_estimates.h"

namespace irdist {
namespace {

TEST_F(HandMadeEstimatesTest, FiguresMatchHandComputedValues) {
  const auto rows = ReadEstimatesCsv((dir_ / "estimates.csv").string());
  ASSERT_EQ(rows.size(), 9u);
  const ValidationSummary s = Summarize(rows);
  ASSERT_EQ(s.methods.size(), 2u);
  const MethodSummary& m = s.methods[0];
  EXPECT_EQ(m.method, "i0_free");
  // Joint rows only: relative errors 0.5, 0.5, 1.0, 0.0, 2.0 %.
  EXPECT_EQ(m.all.count, 5);
  EXPECT_NEAR(m.all.distance_rel_error_pct_median, 0.5, 1e-12);
  EXPECT_NEAR(m.all.distance_rel_error_pct_p95, 1.8, 1e-12);  // 1 + 0.8 * (2 - 1)
  EXPECT_NEAR(m.all.distance_rel_error_pct_max, 2.0, 1e-12);
  EXPECT_NEAR(m.all.distance_abs_error_mm_median, 10.0, 1e-9);
  EXPECT_NEAR(m.all.distance_abs_error_mm_max, 30.0, 1e-9);
  EXPECT_NEAR(m.all.theta_abs_error_deg_median, 1.0, 1e-12);
  EXPECT_NEAR(m.all.theta_abs_error_deg_max, 5.0, 1e-12);
  EXPECT_EQ(m.all.theta_ge15_count, 4);
  EXPECT_NEAR(m.all.theta_ge15_abs_error_deg_median, 0.75, 1e-12);
  EXPECT_NEAR(m.all.theta_ge15_abs_error_deg_max, 2.0, 1e-12);
  EXPECT_EQ(m.all.theta_lt15_count, 1);
  EXPECT_NEAR(m.all.theta_lt15_abs_error_deg_max, 5.0, 1e-12);
  // Means 2000 (475 mA) and 2010 (525 mA) at 2000 mm: 0.5 %.
  ASSERT_TRUE(m.current_shift_pct.has_value());
  EXPECT_NEAR(*m.current_shift_pct, 0.5, 1e-12);
  // Repeats 2010/1990 and 2020/2000: sample sd sqrt(200) mm.
  ASSERT_TRUE(m.dispersion_mm.has_value());
  EXPECT_NEAR(*m.dispersion_mm, std::sqrt(200.0), 1e-9);
  ASSERT_EQ(m.by_dt.size(), 2u);
  EXPECT_NEAR(m.by_dt.at(22.0).distance_rel_error_pct_max, 1.0, 1e-12);
  EXPECT_NEAR(m.by_dt.at(24.0).distance_rel_error_pct_max, 0.2, 1e-12);
  ASSERT_TRUE(m.best_dt_ms.has_value());
  EXPECT_EQ(*m.best_dt_ms, 24.0);
  EXPECT_EQ(m.outside_calibrated_range, 1);

  const MethodSummary* g = s.Find("geometric");
  ASSERT_NE(g, nullptr);
  EXPECT_EQ(g->all.count, 1);
  EXPECT_EQ(g->all.failed, 1);
  EXPECT_NEAR(g->all.distance_rel_error_pct_max, 1.0, 1e-12);
  EXPECT_FALSE(g->current_shift_pct.has_value());
  EXPECT_FALSE(g->dispersion_mm.has_value());
}

// The rows by pose and current keep every repetition's error (the Cramer-Rao comparison's input).
TEST_F(HandMadeEstimatesTest, ConditionsGroupTheRepetitionsOfEachPoseAndCurrent) {
  const auto s = Summarize(ReadEstimatesCsv((dir_ / "estimates.csv").string()));
  const MethodSummary& m = s.methods[0];
  ASSERT_EQ(m.conditions.size(), 3u);
  EXPECT_EQ(m.conditions[0].bias_ma, 475.0);
  EXPECT_EQ(m.conditions[0].d_error_mm, (std::vector<double>{10.0, -10.0}));
  EXPECT_EQ(m.conditions[0].theta_error_deg, (std::vector<double>{1.0, -0.5}));
  EXPECT_EQ(m.conditions[1].d_error_mm, (std::vector<double>{20.0, 0.0}));
  EXPECT_EQ(m.conditions[2].d_mm, 1500.0);
  EXPECT_EQ(m.conditions[2].d_error_mm, (std::vector<double>{30.0}));  // the joint row only
  EXPECT_TRUE(s.methods[1].conditions.size() == 1u);  // the failed geometric row is left out
}

TEST(Percentile, InterpolatesBetweenOrderStatistics) {
  EXPECT_EQ(Percentile({}, 50.0), 0.0);
  EXPECT_EQ(Percentile({3.0, 1.0, 2.0}, 50.0), 2.0);
  EXPECT_NEAR(Percentile({0.0, 10.0}, 95.0), 9.5, 1e-12);
  EXPECT_THROW(Percentile({1.0}, 101.0), CheckError);
}

}  // namespace
}  // namespace irdist
