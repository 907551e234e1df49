#pragma once
// The pixel scans a feature window repeats on every frame, each exact (the same pixels, the same
// sums as a test per pixel) and each a few times cheaper than that test: gray levels above a
// threshold, the run of a row inside a circle, the farthest level above a threshold.

#include <cstdint>
#include <opencv2/core.hpp>

namespace irdist {

// The test "above a threshold" (!(level <= threshold), so a NaN threshold passes every level) on
// whole gray levels: the threshold's floor, compared as an integer; AnyIn takes a row's maximum
// first (a loop the compiler vectorises), so a row with no level above is passed in one sweep.
class LevelAbove {
 public:
  explicit LevelAbove(double threshold);
  bool operator()(std::uint16_t level) const { return level > limit_; }
  bool AnyIn(const std::uint16_t* levels, int n) const;

 private:
  int limit_;  // the highest level not above: -1 .. 65535
};

// The columns [first, last) of row y within [begin, end) inside the circle: those x for which
// !((x - cx) * (x - cx) + (y - cy) * (y - cy) > reach2), evaluated as written (an empty run at
// first = last when none). The circle's chord, its ends settled by that same test per pixel, so
// the run is exactly that test's: the test grows with |x - cx| in floating point too, so its
// pixels are one run. reach2 must not be NaN.
struct ColumnRun {
  int first, last;
};
ColumnRun ColumnsWithin(int y, double cx, double cy, double reach2, int begin, int end);

// The sum of levels[begin, end) (whole numbers: exact, as a double sum of them is).
std::int64_t SumLevels(const std::uint16_t* levels, int begin, int end);

// Squared distance from (cx, cy) of the farthest pixel of `window` (CV_16UC1) above `threshold`
// (0 when none): in each row, the first or the last pixel above it (the distance grows with
// |x - cx|).
double FarthestAbove2(const cv::Mat& image, const cv::Rect& window, double threshold, double cx,
                      double cy);

}  // namespace irdist
