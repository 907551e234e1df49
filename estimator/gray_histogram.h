#pragma once
// Order statistics of gray levels by counting (a histogram over the levels present), for the
// robust background figures the features take on every frame: a median and a median absolute
// deviation over a 256 x 256 square cost two selections over 65 k doubles (1 ms, most of
// ComputeFeatures); counted, they are one pass. Exact: the same order statistics
// std::nth_element gives (the element of rank n / 2), the same clipped sums.

#include <cstdint>
#include <vector>

namespace irdist {

class GrayHistogram {
 public:
  // An empty histogram of the levels 0 .. max_level, filled by Add.
  explicit GrayHistogram(int max_level) : counts_(static_cast<std::size_t>(max_level) + 1, 0) {}
  // The histogram of `levels` (over the range they span).
  explicit GrayHistogram(const std::vector<std::uint16_t>& levels);
  // Counts `n` levels in a row, each at or above the lowest counted (0 for the max_level
  // constructor); the range grows to a level above max_level.
  void AddRun(const std::uint16_t* levels, int n);
  // Counts one level (AddRun of one).
  void Add(std::uint16_t level) { AddRun(&level, 1); }
  std::size_t size() const { return total_; }
  // The level of rank `rank` (0-based) in ascending order; size() > rank required.
  std::uint16_t OrderStatistic(std::size_t rank) const;
  // The element of rank size() / 2 (std::nth_element's middle); 0 when empty.
  double Median() const;
  // The median of |level - median| (rank size() / 2 of the deviations); 0 when empty.
  double MedianAbsoluteDeviation() const;
  // The mean of the levels within `limit` of `centre` (inclusive), and their count in *n.
  double ClippedMean(double centre, double limit, int* n) const;

 private:
  std::uint16_t low_ = 0;
  std::vector<std::uint32_t> counts_;  // counts_[i]: the level low_ + i
  std::size_t total_ = 0;
};

}  // namespace irdist
