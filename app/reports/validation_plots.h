#pragma once
// The figures of a validation's report, as the paper draws them: estimated against true distance
// with a residual panel per current (Fig. 10), the error against the exposure difference
// (Fig. 11-12), (theta, d) and the histogram (Fig. 13), the repetitions (Fig. 14) and the methods
// side by side.

#include <vector>

#include "app/processing/validation_summary.h"
#include "app/reports/plot.h"

namespace irdist {

// The default method's figures (its joint rows when the run has them), then the methods'.
std::vector<Plot> ValidationPlots(const std::vector<EstimateRow>& rows,
                                  const ValidationSummary& summary);

}  // namespace irdist
