#include "estimator/window_scan.h"

#include <algorithm>
#include <cmath>

namespace irdist {

LevelAbove::LevelAbove(double threshold)
    : limit_(!(threshold >= 0.0)    ? -1
             : threshold >= 65535.0 ? 65535
                                    : static_cast<int>(std::floor(threshold))) {}

bool LevelAbove::AnyIn(const std::uint16_t* levels, int n) const {
  if (n <= 0) return false;
  std::uint16_t top = 0;
  for (int i = 0; i < n; ++i) top = std::max(top, levels[i]);
  return top > limit_;
}

ColumnRun ColumnsWithin(int y, double cx, double cy, double reach2, int begin, int end) {
  const auto inside = [&](int x) { return !((x - cx) * (x - cx) + (y - cy) * (y - cy) > reach2); };
  const double half = std::sqrt(std::max(reach2 - (y - cy) * (y - cy), 0.0));
  const auto column = [&](double x, int low) {
    return static_cast<int>(std::clamp(x, static_cast<double>(low), static_cast<double>(end)));
  };
  int first = column(std::ceil(cx - half), begin);
  int last = column(std::floor(cx + half) + 1.0, first);
  while (first > begin && inside(first - 1)) --first;
  while (first < last && !inside(first)) ++first;
  while (last < end && inside(last)) ++last;
  while (last > first && !inside(last - 1)) --last;
  return {first, last};
}

std::int64_t SumLevels(const std::uint16_t* levels, int begin, int end) {
  std::int64_t sum = 0;
  for (int x = begin; x < end; ++x) sum += levels[x];
  return sum;
}

double FarthestAbove2(const cv::Mat& image, const cv::Rect& window, double threshold, double cx,
                      double cy) {
  const LevelAbove above(threshold);
  const int end = window.x + window.width;
  double farthest2 = 0.0;
  for (int y = window.y; y < window.y + window.height; ++y) {
    const std::uint16_t* row = image.ptr<std::uint16_t>(y);
    int first = window.x;
    while (first < end && !above(row[first])) ++first;
    if (first == end) continue;
    int last = end - 1;
    while (!above(row[last])) --last;
    for (const int x : {first, last}) {
      farthest2 = std::max(farthest2, (x - cx) * (x - cx) + (y - cy) * (y - cy));
    }
  }
  return farthest2;
}

}  // namespace irdist
