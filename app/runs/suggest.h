#pragma once
// `irdist plan --suggest`: exposures and bias current for a rig, from a few probe frames (the
// paper's future work). The probes are taken at the two ends of the recipe's working range: the
// nearest distance at theta 0 and the highest current (the brightest image, which must not
// saturate at the longest measurement exposure), and the farthest distance at the largest angle and
// the lowest current (the faintest image, which must carry enough signal at the reference
// exposure). Gray levels are linear in exposure on a linear camera, so two exposures per end give
// the slope and the offset.

#include <optional>
#include <string>
#include <vector>

#include "base/check.h"

namespace irdist {

// One probe frame's measurement.
struct ProbeFrame {
  bool nearest = true;       // true: the bright end; false: the faint end
  double exposure_ms = 0.0;
  double bias_ma = 0.0;
  double peak = 0.0;         // brightest blob pixel, normalised to full scale (0..1)
  double background = 0.0;   // background level, normalised
};

struct SuggestOptions {
  double max_peak_fraction = 0.85;  // brightest pixel at the longest t_n, fraction of full scale
  double min_signal_fraction = 0.08;  // faintest blob's peak above background at t_r, of full scale
  double min_t_ref_ms = 2.0;        // shortest reference exposure worth taking
  double t_step_ms = 2.0;           // spacing of the measurement exposures (the paper's)
  int t_meas_count = 4;             // measurement exposures per bracket (the paper's Table 3)
  std::optional<double> best_dt_ms;  // from the latest validation's summary.yaml, when there is one
  bool IsValid(std::string* why) const;
};

struct Suggestion {
  bool feasible = false;
  double t_ref_ms = 0.0;
  std::vector<double> t_meas_ms;
  double bias_ma = 0.0;
  double nearest_peak_at_longest = 0.0;   // predicted, fraction of full scale
  double farthest_signal_at_ref = 0.0;    // predicted, fraction of full scale
  std::string reason;                     // why these values, or what to change when infeasible
  std::string BriefReport() const;
};

// Throws CheckError when a end has fewer than two probes at distinct exposures.
Suggestion SuggestExposures(const std::vector<ProbeFrame>& probes, const SuggestOptions& options);

}  // namespace irdist
