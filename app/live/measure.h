#pragma once
// `irdist measure`: the calibrated camera as a sensor. Continuous brackets at the model's
// calibration exposures (or the ones given), each estimated as it arrives with the same code as
// validate and playback (EstimateRecordedBracket), printed as a live line on a terminal, one line
// per bracket when piped, or one JSON object per bracket (docs/measure.md). Stops after --count
// brackets, --duration seconds or at Ctrl-C, with a summary (count, rate, mean and sd).
// `--out DIR` writes DIR/estimates.csv as the estimates are made (validate's columns; ground truth
// empty unless --at) and, with --record, DIR/recording/ that `irdist playback` turns into the same
// estimates.csv. Memory does not grow with the run's length (the summary keeps running moments).

#include <cmath>
#include <cstdint>
#include <map>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "app/cli/command_args.h"
#include "app/processing/bracket_estimates.h"
#include "app/reports/summary.h"
#include "estimator/estimate.h"
#include "estimator/features.h"
#include "estimator/health.h"

namespace irdist {

// Version of the per-bracket JSON object (its "schema" field: "irdist.measure/2"). 2:
// flags.outside_range also covers the exposures and the signal level, and a distance or theta
// within 3 standard errors of the calibration's edge is inside (docs/measure.md).
constexpr int kMeasureJsonVersion = 2;

class LiveCamera;  // app/live/live_camera.h

// What one bracket gives: the default (I0-free, joint) estimate and where the blob was.
struct MeasureSample {
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
  Moments d_, theta_, x_, y_, z_, latency_;
};

// The camera taking brackets and estimating each (what measure and view --model run). Starts a
// virtual rig when the rig is one; checks the model's provenance against the camera.
class MeasureSession {
 public:
  // `args` and `model` must outlive the session. Throws CameraError, ModelMismatchError, ...
  MeasureSession(const MeasureArgs& args, const CalibrationModel& model, CommandIo io);
  ~MeasureSession();
  MeasureSession(const MeasureSession&) = delete;
  MeasureSession& operator=(const MeasureSession&) = delete;

  // One bracket; its rows are appended to --out's estimates.csv (synced) before it returns.
  // Throws CameraError when it fails twice, EstimatesFileError, RecordingError.
  MeasureSample Next(double time_s);
  // Why measure must stop before the next bracket ("" = it may go on): with --record, the disk
  // budget (--max-disk-gb) or the disk's free space would not hold another bracket.
  std::string StopReason() const;
  // Stops the stream, closes the recording as complete.
  void Finish();
  const cv::Mat& last_image() const;  // the last frame of the last bracket (CV_16UC1)
  const Features& last_features() const;
  int bit_depth() const;
  // The session's camera (`irdist view` aims with it between brackets).
  LiveCamera& live();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

void RunMeasure(const MeasureArgs& args, CommandIo io);

}  // namespace irdist
