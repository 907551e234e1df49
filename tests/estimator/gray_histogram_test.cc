// The counted order statistics (estimator/gray_histogram.h) against std::nth_element on the same
// levels: the features' background figures must not move when they are counted.
#include "estimator/gray_histogram.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include <gtest/gtest.h>

namespace irdist {
namespace {

double NthMiddle(std::vector<double> values) {
  const auto mid = values.begin() + values.size() / 2;
  std::nth_element(values.begin(), mid, values.end());
  return *mid;
}

double NthMad(const std::vector<std::uint16_t>& levels) {
  std::vector<double> values(levels.begin(), levels.end());
  const double median = NthMiddle(values);
  for (double& v : values) v = std::abs(v - median);
  return NthMiddle(values);
}

std::vector<std::uint16_t> Levels(std::mt19937* rng, int n, double mean, double sd) {
  std::normal_distribution<double> normal(mean, sd);
  std::vector<std::uint16_t> out;
  for (int i = 0; i < n; ++i) {
    out.push_back(static_cast<std::uint16_t>(std::clamp(std::lround(normal(*rng)), 0L, 4095L)));
  }
  return out;
}

TEST(GrayHistogram, MedianAndMadAreNthElementsOnEvenAndOddCounts) {
  std::mt19937 rng(7);
  for (int n : {1, 2, 3, 32, 33, 1000, 65535, 65536}) {
    for (double sd : {0.0, 0.7, 3.0, 400.0}) {
      const std::vector<std::uint16_t> levels = Levels(&rng, n, 180.0 + n % 11, sd);
      const GrayHistogram counted(levels);
      const GrayHistogram added = [&] {
        GrayHistogram h(4095);
        for (std::uint16_t g : levels) h.Add(g);
        return h;
      }();
      const std::vector<double> as_double(levels.begin(), levels.end());
      EXPECT_EQ(counted.Median(), NthMiddle(as_double)) << n << " levels, sd " << sd;
      EXPECT_EQ(counted.MedianAbsoluteDeviation(), NthMad(levels)) << n << " levels, sd " << sd;
      EXPECT_EQ(added.Median(), counted.Median());
      EXPECT_EQ(added.MedianAbsoluteDeviation(), counted.MedianAbsoluteDeviation());
      EXPECT_EQ(counted.size(), levels.size());
    }
  }
}

TEST(GrayHistogram, OrderStatisticsOfASkewedSetAndItsClippedMean) {
  // Mostly background with a bright tail (a blob's wings, a hot pixel): the MAD's deviations are
  // one-sided, and the clipped mean drops the tail exactly as a filtered sum does.
  std::mt19937 rng(11);
  std::vector<std::uint16_t> levels = Levels(&rng, 5000, 200.0, 4.0);
  for (int i = 0; i < 300; ++i) levels.push_back(static_cast<std::uint16_t>(600 + i));
  levels.push_back(4095);
  const GrayHistogram h(levels);
  std::vector<std::uint16_t> sorted = levels;
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t rank : {std::size_t{0}, std::size_t{17}, sorted.size() / 2, sorted.size() - 1}) {
    EXPECT_EQ(h.OrderStatistic(rank), sorted[rank]) << "rank " << rank;
  }
  const double median = h.Median(), limit = 5.0 * 1.4826 * h.MedianAbsoluteDeviation();
  double sum = 0.0;
  int n = 0;
  for (std::uint16_t g : levels) {
    if (std::abs(g - median) > limit) continue;
    sum += g;
    ++n;
  }
  int counted = 0;
  EXPECT_EQ(h.ClippedMean(median, limit, &counted), sum / n);
  EXPECT_EQ(counted, n);
  EXPECT_LT(n, static_cast<int>(levels.size()) - 300);
}

TEST(GrayHistogram, ALevelAboveTheStatedRangeIsCountedNotWrittenPastTheEnd) {
  GrayHistogram h(4095);  // a 12-bit frame that carries a 16-bit level (a wrong bit depth)
  h.Add(100);
  h.Add(65535);
  h.Add(101);
  EXPECT_EQ(h.size(), 3u);
  EXPECT_EQ(h.Median(), 101.0);
  EXPECT_EQ(h.OrderStatistic(2), 65535);
}

// A run counted at once is the same histogram as its levels added one by one, a level beyond
// the constructor's maximum growing it as Add does, an empty run adding nothing.
TEST(GrayHistogram, ARunCountsAsItsLevelsOneByOne) {
  std::mt19937 rng(11);
  std::vector<std::uint16_t> levels = Levels(&rng, 5000, 300.0, 40.0);
  levels[17] = 9000;  // beyond the maximum below
  GrayHistogram one_by_one(1023), in_runs(1023);
  for (std::uint16_t g : levels) one_by_one.Add(g);
  in_runs.AddRun(levels.data(), 2000);
  in_runs.AddRun(levels.data() + 2000, 0);
  in_runs.AddRun(levels.data() + 2000, 3000);
  ASSERT_EQ(in_runs.size(), one_by_one.size());
  for (std::size_t rank : {0UL, 1UL, 2499UL, 2500UL, 4998UL, 4999UL}) {
    EXPECT_EQ(in_runs.OrderStatistic(rank), one_by_one.OrderStatistic(rank)) << rank;
  }
  EXPECT_EQ(in_runs.OrderStatistic(4999), 9000);
  EXPECT_EQ(in_runs.MedianAbsoluteDeviation(), one_by_one.MedianAbsoluteDeviation());
}

TEST(GrayHistogram, EmptyGivesZeros) {
  const GrayHistogram h(std::vector<std::uint16_t>{});
  EXPECT_EQ(h.size(), 0u);
  EXPECT_EQ(h.Median(), 0.0);
  EXPECT_EQ(h.MedianAbsoluteDeviation(), 0.0);
  int n = -1;
  EXPECT_EQ(h.ClippedMean(3.0, 1.0, &n), 3.0);
  EXPECT_EQ(n, 0);
}

}  // namespace
}  // namespace irdist
