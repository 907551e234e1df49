#pragma once
// The figures of a calibration's report: measured against modelled differences (Fig. 7) and the
// Eq. 25 curves of a few samples (Fig. 8).

#include <string>
#include <vector>

#include "app/reports/plot.h"
#include "estimator/fit.h"

namespace irdist {

// One calibration sample as the report shows it (Fig. 7 and Fig. 8).
struct CalibrationPoint {
  double d_mm = 0.0;
  double theta_deg = 0.0;
  double bias_ma = 0.0;
  double dt_ms = 0.0;
  double de_measured = 0.0, de_model = 0.0;  // Delta E_rel and the I0-free model (Eq. 17)
  double ds_measured = 0.0, ds_model = 0.0;  // Delta Sigma and the I0-free model (Eq. 18)
  // Eq. 25 evaluated on a grid of distances (for a handful of samples; empty otherwise).
  std::vector<double> eq25_d_mm;
  std::vector<double> eq25_value;
};

// `model` says whether the dE model (free_e) is a fit at all: a degenerate or ill-conditioned
// one is not drawn as a perfect fit.
std::vector<Plot> CalibrationPlots(const std::vector<CalibrationPoint>& points,
                                   const CalibrationModel& model);

// Why a fitted model's residuals do not measure its fit ("" when they do): degenerate (E
// proportional to F, or a rank-deficient Jacobian) or ill-conditioned.
std::string UnreliableFitReason(const FittedModel& model);

}  // namespace irdist
