#pragma once
// estimates.csv: one row per distance estimate against the station's ground truth, with the
// flags that say what in the scene, the optics or the motion makes it suspect (docs/reports.md).
// Its row type, its writer (whole, or appended bracket by bracket as measure makes them) and its
// one reader.

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "base/check.h"

namespace irdist {

// A flag of an estimate (docs/reports.md, "Flags"): a cause that makes it suspect, or a note of
// what it was measured through, with its figure.
struct EstimateFlag {
  std::string name;    // one of FlagSpecs()' names
  std::string figure;  // the flag's figure with its unit ("3", "8.2px", "+14%"); "" when none
  bool operator==(const EstimateFlag& o) const { return name == o.name && figure == o.figure; }
};

// The documented flags. A note (`suspect` false) says what the estimate was measured through
// and leaves it trusted; any other flag makes it suspect.
struct FlagSpec {
  const char* name;
  bool suspect;
  const char* meaning;  // one line, with the figure's unit
};
const std::vector<FlagSpec>& FlagSpecs();
// The spec of `name`; nullptr when it is not a documented flag.
const FlagSpec* FindFlagSpec(const std::string& name);
// Whether `flags` holds the flag `name`.
bool HasFlag(const std::vector<EstimateFlag>& flags, const char* name);
// estimates.csv's flags cell: "name" or "name=figure", separated by spaces ("" when none).
std::string FlagsCell(const std::vector<EstimateFlag>& flags);
// The flags of a cell written by FlagsCell. Throws EstimatesFileError naming `where` on a name
// that is not documented.
std::vector<EstimateFlag> ParseFlagsCell(const std::string& cell, const std::string& where);

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
  // Standard errors of d_mm and theta_deg from the solver (-1 or NaN: not computed; an empty
  // cell of estimates.csv's d_se_mm and theta_se_deg).
  double d_std_mm = -1.0;
  double theta_std_deg = -1.0;
  // 3D position in the camera frame (mm) and its standard errors when the rig has intrinsics
  // (app/processing/position.h), and its ground truth on a virtual rig; NaN (empty in the CSV)
  // otherwise.
  double x_mm = NAN, y_mm = NAN, z_mm = NAN;
  double x_se_mm = NAN, y_se_mm = NAN, z_se_mm = NAN;
  double true_x_mm = NAN, true_y_mm = NAN, true_z_mm = NAN;
  // Calibration health (estimator/health.h): "ok", "-" (not assessed), "blur_larger" or
  // "blur_smaller" (the optics no longer match the calibration).
  std::string health = "-";
  // Motion inside the bracket (estimator/bracket_checks.h CheckMotionOfSizes, or CheckMotion on
  // the moments path), on the default method's joint row: "moving", "static", or "-" (not
  // assessed); spread_mm = largest minus smallest of the frames' (or exposures') distances.
  std::string motion = "-";
  double spread_mm = NAN;
  // The calibrated ranges the estimate lies outside (estimator/bracket_checks.h OutsideRanges:
  // "distance", "theta", "t_ref", "t_meas", "signal"); outside_range = !outside.empty().
  std::vector<std::string> outside;
  // When the bracket's data was complete: its last frame's arrival on the host's wall clock (ns
  // since the Unix epoch; estimates.csv column utc_time, ISO 8601 UTC with microseconds), the
  // host's monotonic clock then (host_monotonic_ns) and the camera's own timestamp of that frame
  // (camera_timestamp_ns). 0 = unknown (an empty cell).
  std::int64_t utc_ns = 0;
  std::int64_t host_monotonic_ns = 0;
  std::uint64_t camera_timestamp_ns = 0;
  // What makes this estimate suspect, and the notes of what it was measured through
  // (app/processing/estimate_flags.h); estimates.csv's flags column.
  std::vector<EstimateFlag> flags;
  // No suspect flag (notes only) on an estimate that was made.
  bool Trusted() const;
};

class EstimatesFileError : public Error {
 public:
  using Error::Error;
};

// "a;b" from {"a", "b"} ("" when empty): estimates.csv's outside column.
std::string JoinNames(const std::vector<std::string>& names, const char* separator = ";");

// estimates.csv: header line then one row per estimate, bracket after bracket (columns in
// docs/reports.md). Throws EstimatesFileError.
void WriteEstimatesCsv(const std::string& path, const std::vector<EstimateRow>& rows);
// Reads every complete row. A last line without its end of line (the writer was killed or the
// power cut while writing it) is dropped, and `*note` (when given) says so; "" otherwise. Empty
// ground-truth cells (irdist measure without --at) read as NaN. Throws EstimatesFileError.
std::vector<EstimateRow> ReadEstimatesCsv(const std::string& path, std::string* note = nullptr);

// estimates.csv written as the estimates are made (irdist measure): Open writes the header, each
// Append writes its rows with one write(2) and syncs the file (fdatasync), so a kill -9 or a power
// cut loses at most the rows being written, and a reader drops a torn last line.
class EstimatesCsvWriter {
 public:
  // Creates (or replaces) `path` and writes the header. Throws EstimatesFileError.
  explicit EstimatesCsvWriter(const std::string& path);
  ~EstimatesCsvWriter();
  EstimatesCsvWriter(const EstimatesCsvWriter&) = delete;
  EstimatesCsvWriter& operator=(const EstimatesCsvWriter&) = delete;
  void Append(const std::vector<EstimateRow>& rows);  // throws EstimatesFileError

 private:
  void WriteAll(const std::string& text);
  std::string path_;
  int fd_ = -1;
};

}  // namespace irdist
