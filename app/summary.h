#pragma once
// Validation figures from per-bracket estimates: what summary.yaml holds (docs/reports.md).
// Pure computation over rows, so the same numbers come from a live run and from playback.

#include <cmath>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "base/check.h"

namespace irdist {

// One distance estimate against the station's ground truth (one row of estimates.csv).
struct EstimateRow {
  int bracket = 0;     // bracket id in the recording
  int pose = 0;        // pose index of the sweep (same slide/pan/tilt/current)
  int repeat = 0;      // repetition of the pose
  std::string method;  // "i0_free", "i0_dependent", "geometric", ...
  double dt_ms = 0.0;  // exposure difference; 0 = joint estimate over every t_n of the bracket
  double true_d_mm = 0.0;
  double true_theta_deg = 0.0;
  double bias_ma = 0.0;        // current as set for this bracket
  double d_mm = 0.0;           // estimate
  double theta_deg = 0.0;      // estimate
  bool outside_range = false;  // the estimate lies outside the calibrated range
  bool ok = true;              // false: no estimate (no root, no blob): counted, not averaged
  // Standard errors of d_mm and theta_deg from the solver (-1 or NaN: not computed). Not in
  // estimates.csv.
  double d_std_mm = -1.0;
  double theta_std_deg = -1.0;
  // 3D position in the camera frame (mm) and its standard errors when the rig has intrinsics
  // (app/position.h), and its ground truth on a virtual rig; NaN (empty in the CSV) otherwise.
  double x_mm = NAN, y_mm = NAN, z_mm = NAN;
  double x_se_mm = NAN, y_se_mm = NAN, z_se_mm = NAN;
  double true_x_mm = NAN, true_y_mm = NAN, true_z_mm = NAN;
  // Calibration health (estimator/health.h): "ok", "-" (not assessed), "blur_larger" or
  // "blur_smaller" (the optics no longer match the calibration).
  std::string health = "-";
};

class EstimatesFileError : public Error {
 public:
  using Error::Error;
};

// estimates.csv: header line then one row per estimate (columns in docs/reports.md).
void WriteEstimatesCsv(const std::string& path, const std::vector<EstimateRow>& rows);
std::vector<EstimateRow> ReadEstimatesCsv(const std::string& path);  // throws EstimatesFileError

struct ErrorFigures {
  int count = 0;
  int failed = 0;  // rows with ok == false
  double distance_rel_error_pct_median = 0.0;
  double distance_rel_error_pct_p95 = 0.0;
  double distance_rel_error_pct_max = 0.0;
  double distance_abs_error_mm_median = 0.0;
  double distance_abs_error_mm_max = 0.0;
  // theta error, all rows / rows with true theta >= 15 deg / rows below.
  double theta_abs_error_deg_median = 0.0;
  double theta_abs_error_deg_max = 0.0;
  double theta_ge15_abs_error_deg_median = 0.0;
  double theta_ge15_abs_error_deg_max = 0.0;
  int theta_ge15_count = 0;
  double theta_lt15_abs_error_deg_median = 0.0;
  double theta_lt15_abs_error_deg_max = 0.0;
  int theta_lt15_count = 0;
};

struct MethodSummary {
  std::string method;
  ErrorFigures all;                         // the default rows (joint over t_n when present)
  std::optional<double> current_shift_pct;  // needs >= 2 currents at one pose
  std::optional<double> dispersion_mm;      // needs >= 2 repetitions of one pose
  std::map<double, ErrorFigures> by_dt;     // per exposure difference (dt_ms > 0 rows)
  std::optional<double> best_dt_ms;         // smallest median relative error among by_dt
  int outside_calibrated_range = 0;
  int health_assessed = 0;  // default rows whose health was assessed
  int health_flagged = 0;   // ... and flagged (the optics no longer match the calibration)
};

struct ValidationSummary {
  std::vector<MethodSummary> methods;  // in order of first appearance
  const MethodSummary* Find(const std::string& method) const;
  std::string BriefReport() const;
};

// Percentile by linear interpolation between order statistics (p in [0, 100]).
double Percentile(std::vector<double> values, double p);

ValidationSummary Summarize(const std::vector<EstimateRow>& rows);

// The top-level best_dt_ms of a summary.yaml (nullopt when it is null). Throws EstimatesFileError
// naming the file when it cannot be read.
std::optional<double> ReadBestDtMs(const std::string& summary_yaml_path);

// summary.yaml: `count`, `distance_rel_error_pct: {median, p95, max}`, ... for the first method at
// top level (the default pipeline), and one block per other method (`i0_dependent:`, `geometric:`).
void WriteSummaryYaml(const std::string& path, const ValidationSummary& summary,
                      const std::map<std::string, std::string>& context = {});

}  // namespace irdist
