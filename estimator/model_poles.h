#pragma once
// A ratio model's poles inside its calibrated domain. Eq. 17 and Eq. 18 are ratios Num / Den, and
// a least-squares fit on a grid with few distances can place a zero of Den on the grid itself with
// a zero of Num beside it: the calibration's own samples are fitted (0/0 tuned to their values),
// the model between them is not. Measured 2026-12-04 on the virtual rig, a 3-distance grid (1500,
// 2000, 2500 mm): Eq. 18's denominator factored as (rho + 0.38) (D - D(2000 mm)), and every
// bracket at 2100 and 3000 mm read 2000.0 mm with a standard error of 1e-6 mm. A model is judged
// where the estimator will use it: for each sample's exposures and signal (dt, dF), the distance
// swept over the calibrated range widened by the estimator's margin (its roots count "in range"
// there, EstimateOptions::range_margin) and theta over the calibrated thetas (rho at the fit's
// sigma). A zero on the range's edge is a pole too: on a 3-distance grid's halo-lens calibration
// (seed 16) Num and Den both vanished at exactly 2500 mm, the scan from the edge saw no sign change
// and no tiny value (3e-7 of the sample's), and every bracket at 2300 mm read 2500.0 mm +- 2e-5.

#include <array>
#include <string>
#include <vector>

#include "estimator/models.h"

namespace irdist {

// How far beyond the calibrated distances the estimator takes a root as "in range", relative
// (EstimateOptions::range_margin's default): the domain a model's poles are looked for in.
constexpr double kDefaultRangeMargin = 0.10;

struct PoleScan {
  bool pole = false;     // Den vanishes (changes sign, or falls below 1e-9 of its value at a
                         // sample) somewhere in the domain
  double d_mm = 0.0;     // where (the first found), for the message
  double theta_deg = 0.0;
  // "its denominator vanishes at d = 2000 mm, theta 10 deg, inside the calibrated range (or its
  // margin)" or "".
  std::string Note() const;
};

// samples: the scaled variables of each calibration observation (rho ignored); thetas: their
// thetas (deg); sigma_deg: the model's. d_ref_mm and d_scale map D = (d_ref / d)^2 / d_scale back
// to mm for the note. The distances swept: the samples' [d_min / (1 + margin), d_max * (1 +
// margin)]. Models without a denominator have no pole.
PoleScan ScanForPoles(const ModelSpec& spec, const std::vector<double>& coefficients,
                      double sigma_deg,
                      const std::vector<std::array<double, kNumModelVars>>& samples,
                      const std::vector<double>& thetas_deg, double d_ref_mm, double d_scale,
                      double margin);

}  // namespace irdist
