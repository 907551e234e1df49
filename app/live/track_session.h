#pragma once
// `irdist measure --track` (docs/measure.md "Tracking"): the camera runs continuously at one
// exposure (the model's reference exposure or --exposure-ms, inside the calibrated exposures),
// triggered frame after frame `ahead` triggers in advance (app/live/frame_grabber.h); each frame
// the estimator takes gives one estimate (app/live/track_estimate.h) with the frame's camera and
// UTC times, smoothed by a constant-velocity filter on the distance (estimator/track_filter.h,
// --accel-psd its process noise). With --check-every S a full bracket of measure (the same
// MeasureSession) is taken every S seconds as the radiometric cross-check, and says whether it
// agrees with the track. Frames the estimator could not keep up with are counted, never hidden.

#include <memory>
#include <string>

#include "app/inputs/command_args.h"
#include "app/live/track_output.h"
#include "estimator/fit.h"

namespace irdist {

// The exposure the track runs at (ms): --exposure-ms, else the model's reference exposure.
// Throws UsageError when there is none, or when it lies outside the calibrated exposures
// (reference and measurement ranges of model.yaml, 0.1% tolerance).
double TrackExposureMs(const MeasureArgs& args, const CalibrationModel& model);

class TrackSession {
 public:
  // `args` and `model` must outlive the session. Throws UsageError, CameraError, ...
  TrackSession(const MeasureArgs& args, const CalibrationModel& model, CommandIo io);
  ~TrackSession();
  TrackSession(const TrackSession&) = delete;
  TrackSession& operator=(const TrackSession&) = delete;

  // How the camera runs: "track: triggered (...), exposure ..., the camera's bound ... frames/s".
  std::string Header() const;
  // The next line: a bracket check when one is due, else the newest frame's estimate (waiting
  // for it). `time_s`: host seconds since the run started. Throws CameraError when no frame
  // comes.
  TrackSample Next(double time_s);
  // Stops the grabbing and the camera's stream.
  void Finish();
  TrackCounters counters() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The command (cli.cc runs it for `measure --track`): the model loaded, lines until --count
// frames, --duration, Ctrl-C or a closed stdout, then the summary (stderr with --json). Refuses
// --out and --record (UsageError): a track writes only its lines.
void RunTrack(const MeasureArgs& args, CommandIo io);

// The `measure` command: RunTrack with --track, else RunMeasure's brackets (app/live/measure.h).
void RunMeasureOrTrack(const MeasureArgs& args, CommandIo io);

}  // namespace irdist
