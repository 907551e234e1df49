#pragma once
// An edge correction's table for tests and benchmarks (estimator/edge_correction.h): a ringing of
// `amplitude` (a share of the disc's brightness) and 1.7 px period over the edge, tapered to 0
// over the table's outer pixel as a calibration's is.

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "estimator/blur_model.h"

namespace irdist::testing {

inline std::shared_ptr<const std::vector<double>> RingingEdgeCorrection(double amplitude) {
  auto table = std::make_shared<std::vector<double>>(kEdgeCorrectionKnots);
  for (int k = 0; k < kEdgeCorrectionKnots; ++k) {
    const double t = k * kEdgeCorrectionStepPx - kEdgeCorrectionHalfWidthPx;
    const double taper =
        std::sin(0.5 * M_PI * std::min(kEdgeCorrectionHalfWidthPx - std::abs(t), 1.0));
    (*table)[k] = amplitude * std::sin(2.0 * M_PI * t / 1.7) * taper * taper;
  }
  return table;
}

}  // namespace irdist::testing
