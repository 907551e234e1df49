#include "estimator/gray_histogram.h"

#include <algorithm>
#include <cmath>

#include "base/check.h"

namespace irdist {

GrayHistogram::GrayHistogram(const std::vector<std::uint16_t>& levels) : total_(levels.size()) {
  if (levels.empty()) return;
  const auto [lo, hi] = std::minmax_element(levels.begin(), levels.end());
  low_ = *lo;
  counts_.assign(static_cast<std::size_t>(*hi - *lo) + 1, 0);
  for (std::uint16_t g : levels) ++counts_[g - low_];
}

void GrayHistogram::AddRun(const std::uint16_t* levels, int n) {
  std::uint32_t* counts = counts_.data();
  std::size_t bins = counts_.size();
  for (int i = 0; i < n; ++i) {
    const std::size_t bin = static_cast<std::size_t>(levels[i] - low_);
    if (bin >= bins) {
      counts_.resize(bin + 1, 0);
      counts = counts_.data();
      bins = counts_.size();
    }
    ++counts[bin];
  }
  total_ += static_cast<std::size_t>(std::max(n, 0));
}

std::uint16_t GrayHistogram::OrderStatistic(std::size_t rank) const {
  IRDIST_CHECK(rank < total_, "rank ", rank, " of ", total_, " levels");
  std::size_t seen = 0;
  for (std::size_t i = 0; i < counts_.size(); ++i) {
    seen += counts_[i];
    if (seen > rank) return static_cast<std::uint16_t>(low_ + i);
  }
  return static_cast<std::uint16_t>(low_ + counts_.size() - 1);
}

double GrayHistogram::Median() const { return total_ == 0 ? 0.0 : OrderStatistic(total_ / 2); }

double GrayHistogram::MedianAbsoluteDeviation() const {
  if (total_ == 0) return 0.0;
  const std::size_t median = OrderStatistic(total_ / 2) - low_;
  // The deviations' histogram: bin k holds the levels median - k and median + k.
  const std::size_t reach = std::max(median, counts_.size() - 1 - median);
  std::size_t seen = 0;
  for (std::size_t k = 0; k <= reach; ++k) {
    if (k <= median) seen += counts_[median - k];
    if (k > 0 && median + k < counts_.size()) seen += counts_[median + k];
    if (seen > total_ / 2) return static_cast<double>(k);
  }
  return static_cast<double>(reach);
}

double GrayHistogram::ClippedMean(double centre, double limit, int* n) const {
  double sum = 0.0;
  std::size_t count = 0;
  for (std::size_t i = 0; i < counts_.size(); ++i) {
    const double level = static_cast<double>(low_ + i);
    if (counts_[i] == 0 || std::abs(level - centre) > limit) continue;
    sum += level * counts_[i];
    count += counts_[i];
  }
  *n = static_cast<int>(count);
  return count > 0 ? sum / static_cast<double>(count) : centre;
}

}  // namespace irdist
