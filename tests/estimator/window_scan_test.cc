// The window scans (estimator/window_scan.h) against the per-pixel tests they replace: the same
// pixels, the same sums, for every threshold a feature can pass (NaN and out-of-range included).
#include "estimator/window_scan.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

namespace irdist {
namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

TEST(LevelAbove, IsTheDoubleTestOnEveryLevelAndThreshold) {
  const std::vector<std::uint16_t> levels = {0, 1, 99, 100, 101, 4095, 32767, 32768, 65534, 65535};
  const std::vector<double> thresholds = {kNaN,   -kInf,   -1.0,  -0.5,  0.0,
                                          0.5,    99.999,  100.0, 100.5, 4094.99,
                                          4095.0, 65534.5, 65535, 7e4,   kInf};
  for (double t : thresholds) {
    const LevelAbove above(t);
    for (std::uint16_t g : levels) {
      EXPECT_EQ(above(g), !(g <= t)) << "level " << g << ", threshold " << t;
    }
  }
}

TEST(LevelAbove, AnyInFindsALevelAboveWherePresent) {
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> level(0, 65535), length(0, 70);
  for (int trial = 0; trial < 2000; ++trial) {
    std::vector<std::uint16_t> row(static_cast<std::size_t>(length(rng)));
    for (auto& g : row) g = static_cast<std::uint16_t>(level(rng) % (trial % 7 == 0 ? 200 : 65536));
    const double t = trial % 5 == 0 ? kNaN : level(rng) + 0.25 * (trial % 4) - 1.0;
    const bool any =
        std::any_of(row.begin(), row.end(), [t](std::uint16_t g) { return !(g <= t); });
    EXPECT_EQ(LevelAbove(t).AnyIn(row.data(), static_cast<int>(row.size())), any)
        << "trial " << trial;
  }
}

TEST(ColumnsWithin, IsExactlyThePixelsThatPassTheTest) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> centre(-20.0, 84.0), radius(0.0, 40.0);
  for (int trial = 0; trial < 3000; ++trial) {
    const double cx = centre(rng), cy = centre(rng);
    const double r = trial % 50 == 0 ? 0.0 : radius(rng);
    const double reach2 = trial % 3 == 0 ? std::round(r * r) : r * r;  // on pixel centres too
    const int begin = trial % 4, end = 64 - trial % 5;
    for (int y = -2; y < 66; ++y) {
      const ColumnRun run = ColumnsWithin(y, cx, cy, reach2, begin, end);
      ASSERT_LE(begin, run.first);
      ASSERT_LE(run.first, run.last);
      ASSERT_LE(run.last, end);
      for (int x = begin; x < end; ++x) {
        const bool inside = !((x - cx) * (x - cx) + (y - cy) * (y - cy) > reach2);
        ASSERT_EQ(inside, x >= run.first && x < run.last)
            << "x " << x << " y " << y << " centre " << cx << ", " << cy << " reach2 " << reach2;
      }
    }
  }
}

TEST(SumLevels, SumsTheRange) {
  const std::vector<std::uint16_t> levels = {65535, 65535, 7, 0, 12};
  EXPECT_EQ(SumLevels(levels.data(), 0, 5), 131089);
  EXPECT_EQ(SumLevels(levels.data(), 2, 4), 7);
  EXPECT_EQ(SumLevels(levels.data(), 3, 3), 0);
}

double BruteFarthestAbove2(const cv::Mat& image, const cv::Rect& w, double t, double cx,
                           double cy) {
  double best = 0.0;
  for (int y = w.y; y < w.y + w.height; ++y) {
    for (int x = w.x; x < w.x + w.width; ++x) {
      if (image.at<std::uint16_t>(y, x) <= t) continue;
      best = std::max(best, (x - cx) * (x - cx) + (y - cy) * (y - cy));
    }
  }
  return best;
}

TEST(FarthestAbove2, IsTheFarthestPixelAboveTheThreshold) {
  std::mt19937 rng(9);
  std::uniform_int_distribution<int> sparse(0, 99), level(0, 4095);
  std::uniform_real_distribution<double> centre(-10.0, 50.0);
  for (int trial = 0; trial < 500; ++trial) {
    cv::Mat image(40, 48, CV_16UC1);
    for (int y = 0; y < image.rows; ++y) {
      for (int x = 0; x < image.cols; ++x) {
        image.at<std::uint16_t>(y, x) =
            static_cast<std::uint16_t>(sparse(rng) < trial % 30 ? level(rng) : 100);
      }
    }
    const cv::Rect window(trial % 6, trial % 5, 40, 32);
    const double t = trial % 17 == 0 ? kNaN : trial % 11 == 0 ? 100.0 : 90.0 + level(rng) * 0.9;
    const double cx = centre(rng), cy = centre(rng);
    EXPECT_EQ(FarthestAbove2(image, window, t, cx, cy),
              BruteFarthestAbove2(image, window, t, cx, cy))
        << "trial " << trial;
  }
}

}  // namespace
}  // namespace irdist
