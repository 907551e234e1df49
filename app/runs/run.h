#pragma once
// The live runs behind the irdist commands: calibrate and validate (sweep a recipe on a rig, record,
// then fit or estimate), and the recording they share with plan --suggest's probe
// (app/runs/run_suggest.h). The offline commands are declared in app/runs/fit_command.h,
// app/runs/playback_command.h and app/runs/check_command.h.
//
// Run folder layout (always the same):
//   DIR/recording/      the recording (docs/recording-format.md)
//   DIR/station.log     every line sent to and received from the station
//   DIR/features.csv    per-frame features (docs/reports.md)
//   DIR/model.yaml      calibrate: the calibration (docs/estimator.md)
//   DIR/estimates.csv   validate: per-bracket estimates; DIR/summary.yaml: the figures
//   DIR/report/index.html
// A resumed run keeps the earlier sessions' station logs as station.<n>.log.

#include <memory>
#include <string>

#include "app/inputs/command_args.h"
#include "app/inputs/errors.h"
#include "app/processing/frame_features.h"
#include "app/runs/run_folder.h"

namespace irdist {

// Throw InterruptedError after a Ctrl-C (recording closed as cut), RecipeError, CameraError,
// LinkError, StationError, RecordingError, ModelFileError.
void RunCalibrate(const CalibrateArgs& args, CommandIo io);
void RunValidate(const ValidateArgs& args, CommandIo io);

// The recording phase every live run shares (calibrate, validate, plan --suggest's probe in
// app/runs/run_suggest.cc): what it is asked to do, and what it leaves.
struct RunRequest {
  RunKind kind = RunKind::kCalibrate;
  std::string recipe_path;
  std::string model_path;  // validate
  std::string out_dir;
  std::string resume_dir;
  double time_scale = 0.0;
  bool quiet = false;
  bool allow_model_mismatch = false;  // validate
  bool allow_nonlinear = false;       // calibrate: --allow-nonlinear
  bool keep_model = false;            // calibrate: --keep-model
  // validate on hardware: the model's camera serial, which AravisCamera::Open then requires
  // ("" = none: another camera is allowed, or the model does not say).
  std::string expected_serial;
};

// What the recording phase leaves for the processing phase.
struct Recorded {
  std::string dir;
  FeatureMap cache;  // features of the frames captured in this session
  bool cut = false;
  std::unique_ptr<RunFolderLock> lock;  // held through the processing too
};

struct Recipe;
struct Plan;
// Records `plan` of `recipe` into a new run folder or the one resumed (OpenRunFolder, locked in
// the result), with the features computed as the brackets are committed: starts the rig, the
// station and the camera, sweeps, and reports the sweep, the capture and the time on io.out. A
// stop leaves the recording cut (Recorded::cut); a failure closes it as cut, prints the --resume
// command and rethrows.
Recorded Record(const RunRequest& request, const Recipe& recipe, const Plan& plan,
                const FeatureOptions& feature_options, const CalibrationModel* blob_fit_model,
                CommandIo io);

}  // namespace irdist
