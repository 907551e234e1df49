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

#include "app/inputs/command_args.h"
#include "app/live/measure_output.h"
#include "app/processing/bracket_estimates.h"
#include "app/processing/estimates_csv.h"
#include "estimator/estimate.h"
#include "estimator/features.h"
#include "estimator/health.h"

namespace irdist {

class LiveCamera;  // app/live/live_camera.h

// The camera taking brackets and estimating each (what measure and view --model run). Starts a
// virtual rig when the rig is one; checks the model's provenance against the camera.
class MeasureSession {
 public:
  // `args` and `model` must outlive the session. Throws CameraError, ModelMismatchError, ...
  // quiet_rig: no progress from the camera and the station on io.err, as with --json (`irdist
  // view` measures under its own window).
  MeasureSession(const MeasureArgs& args, const CalibrationModel& model, CommandIo io,
                 bool quiet_rig = false);
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
