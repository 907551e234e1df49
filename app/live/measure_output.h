#pragma once
// What `irdist measure` shows of each bracket: the sample (the default estimate, the blob, the
// flags), its JSON object (schema irdist.measure/2, docs/measure.md), its one-line text form and
// the run's summary. The Python module (python/) returns the same JSON objects.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "app/processing/bracket_estimates.h"
#include "app/processing/estimates_csv.h"
#include "estimator/bracket_checks.h"
#include "estimator/estimate.h"
#include "estimator/health.h"

namespace irdist {

struct CameraGeometry;
struct RecordedBracket;

// Version of the per-bracket JSON object (its "schema" field: "irdist.measure/2"). 2:
// flags.outside_range also covers the exposures and the signal level, and a distance or theta
// within 3 standard errors of the calibration's edge is inside (docs/measure.md). Added within 2:
// `trusted`, `causes` (every flag of app/processing/estimate_flags.h with its figure),
// flags.second_source and flags.occluded.
constexpr int kMeasureJsonVersion = 2;

// What one bracket gives: the default (I0-free, joint) estimate and where the blob was.
struct MeasureSample {
  // "bracket" (measure's) or "track" (one frame of `measure --track`, app/live/track_session.h):
  // the JSON's `mode`.
  const char* mode = "bracket";
  std::int64_t bracket = 0;
  double time_s = 0.0;  // host seconds since the first bracket started
  // The bracket's last frame: its arrival on the host's wall clock (ns since the Unix epoch, UTC)
  // and on its monotonic clock (both stamped by the grabber), and the camera's own timestamp of
  // it (0: the camera gave none).
  std::int64_t utc_ns = 0;
  std::int64_t host_monotonic_ns = 0;
  std::uint64_t camera_timestamp_ns = 0;
  // Host ms from the bracket's last frame (handed over by the grabber) to its estimate; the frames'
  // features are computed as they arrive, so this is the last frame's features and the solve
  // (and, with --record, the recording's writes).
  double latency_ms = std::nan("");
  EstimateRow estimate;  // the i0_free joint row
  bool have_estimate = false;
  double blob_x_px = 0.0, blob_y_px = 0.0;  // centroid in the sensor's pixels
  bool blob_found = false;
  bool saturated = false, touches_border = false, clipped = false;
  // 3D position in the camera frame (mm), when the rig has intrinsics.
  bool has_position = false;
  double x_mm = 0.0, y_mm = 0.0, z_mm = 0.0;
  double x_se_mm = 0.0, y_se_mm = 0.0, z_se_mm = 0.0;
  // The bracket's calibration health and motion (the estimate's outside ranges are in `estimate`).
  HealthCheck health;
  MotionCheck motion;
};

// The sample of one estimated bracket: the default estimate (`rows` of EstimateRecordedBracket),
// the blob of its last frame in sensor pixels (the frames' ROI offset from `geometry`) and the
// quality flags of all its frames. measure's and the Python module's (python/) one path.
MeasureSample MeasureSampleOf(const RecordedBracket& bracket, const FeatureMap& features,
                              const BracketEstimateRows& rows, const CalibrationModel& model,
                              const CameraGeometry& geometry);

// `value` with `decimals` decimals, "-" when not finite: the text of every figure measure prints.
std::string FixedText(double value, int decimals);

// A JSON number (%.10g), "null" when not finite.
std::string JsonNumber(double value);
// The JSON object of one bracket (one line, no trailing newline).
std::string MeasureJson(const MeasureSample& s);
// The one-line text form (piped output; the terminal's live line is the same text).
std::string MeasureLine(const MeasureSample& s);
// The live line cut to fit `width_chars` columns (one short of it, so it never wraps): the fields
// that matter least (time, blob, xyz, theta) are dropped first; the distance and flags stay.
std::string MeasureLine(const MeasureSample& s, std::size_t width_chars);
// The terminal's width in columns (TIOCGWINSZ) when `fd` is a terminal, else 80.
std::size_t TerminalWidthChars(int fd);
// The quality flags of a sample, comma-separated ("ok" when none).
std::string QualityFlags(const MeasureSample& s);

// Count, rate, mean and sd of each quantity over the samples with an estimate.
class MeasureStats {
 public:
  void Add(const MeasureSample& s);
  std::string Report(double wall_s) const;
  int count() const { return count_; }

 private:
  struct Moments {
    int n = 0;
    double mean = 0.0, m2 = 0.0;
    void Add(double value);
    double Sd() const;
  };
  int count_ = 0;
  int estimated_ = 0;
  int unhealthy_ = 0, health_assessed_ = 0, moving_ = 0, motion_assessed_ = 0, outside_ = 0;
  std::map<std::string, int> outside_by_range_;
  int suspect_ = 0;
  std::map<std::string, int> by_flag_;  // the estimates' flags by name
  Moments d_, theta_, x_, y_, z_, latency_;
};

}  // namespace irdist
