#pragma once
// What every irdist command receives: its output streams and its parsed flags, one Args struct per
// subcommand. A leaf header (no app/ include) so that each command's header (runs/run.h: live
// runs, runs/fit_command.h, runs/playback_command.h and runs/check_command.h: the offline ones,
// devices/sim_command.h and devices/devices_command.h, live/measure.h, live/snap_command.h and
// live/view.h: the camera-only commands, cli/cli.h: parsing and dispatch) declares its own
// commands without including another's. Each Args struct with numbers has IsValid(&why), the
// same bounds as the command line's checks (base/bounds.h), so that an engine called from a test,
// a script or another command refuses what the parser would have refused (the command's entry
// point checks it first and throws UsageError with `why`).

#include <iosfwd>
#include <string>
#include <vector>

namespace irdist {

// Throws UsageError "irdist COMMAND: WHY" (app/inputs/errors.h).
[[noreturn]] void RefuseArgs(const char* command, const std::string& why);

// An engine's first step: its Args as the command line would have taken them, or UsageError.
template <typename Args>
void RequireValid(const Args& args, const char* command) {
  std::string why;
  if (!args.IsValid(&why)) RefuseArgs(command, why);
}

// Limits of flags outside base/bounds.h's physical table, shared by the parser (cli/) and IsValid.
inline constexpr double kMaxAtValue = 1.0e6;    // --at: each of SLIDE_MM, PAN_DEG, TILT_DEG, BIAS_MA
inline constexpr int kMaxShownPoses = 1000000;  // plan --poses

struct CommandIo {
  std::ostream& out;  // results
  std::ostream& err;  // progress and diagnostics
};

struct CalibrateArgs {
  std::string recipe;       // recipe file
  std::string out_dir;      // --out: overrides the recipe's output directory ("" = recipe's)
  std::string resume_dir;   // --resume: continue a cut run from its recording ("" = new run)
  double time_scale = 0.0;  // --time-scale: virtual rig's simulated s per host s (0 = rig file's)
  bool quiet = false;       // --quiet: no progress output
  bool allow_nonlinear = false;  // --allow-nonlinear: go on past a failed first-pose linearity
  bool keep_model = false;  // --keep-model: model.yaml even when the fit fails its fitness

  bool IsValid(std::string* why) const;
};

struct ValidateArgs {
  std::string recipe;
  std::string model;  // --model: model.yaml from a calibration
  std::string out_dir;
  std::string resume_dir;
  double time_scale = 0.0;
  bool quiet = false;
  bool allow_model_mismatch = false;  // --allow-model-mismatch: a model of another camera setup

  bool IsValid(std::string* why) const;
};

struct FitArgs {
  std::string recording;  // recording folder
  std::string out;        // --out: model file to write ("" = RECORDING/../model.yaml)
  bool recover_response = false;  // --recover-response: the camera's inverse response first
  bool force = false;             // --force: replace an existing model.yaml, features.csv, report
  bool keep_model = false;  // --keep-model: model.yaml even when the fit fails its fitness
};

struct PlaybackArgs {
  std::string recording;
  std::string model;    // --model
  std::string out_dir;  // --out ("" = beside the recording)
  bool show = false;    // --show: step through the frames in an OpenCV window
  bool force = false;   // --force: replace existing features.csv, estimates.csv, summary, report
  bool allow_model_mismatch = false;  // --allow-model-mismatch
};

// `irdist measure`: continuous brackets on the camera alone, one estimate each
// (app/live/measure.h).
struct MeasureArgs {
  std::string model;            // --model: model.yaml from a calibration
  std::string rig = "virtual";  // --rig: rig name or file
  double t_ref_ms = 0.0;        // --t-ref-ms (0 = the model's calibration bracket)
  std::vector<double> t_meas_ms;  // --t-meas-ms (empty = the model's)
  int count = 0;                // --count: stop after N brackets (0 = until Ctrl-C / duration)
  double duration_s = 0.0;      // --duration: stop after S host seconds (0 = no limit)
  bool json = false;            // --json: one JSON object per bracket on stdout
  std::string out_dir;          // --out: estimates.csv (and recording/ with --record)
  bool record = false;          // --record: the frames in the recording format
  double max_disk_gb = 0.0;     // --max-disk-gb: the recording's budget (0 = free space margin only)
  std::vector<double> at;       // --at SLIDE_MM,PAN_DEG,TILT_DEG,BIAS_MA (virtual rig only)
  double time_scale = 0.0;      // --time-scale (virtual rig; 0 = rig file's)
  bool allow_model_mismatch = false;
  // --track (docs/measure.md "Tracking"): an estimate per frame at one exposure, smoothed by a
  // constant-velocity filter; --count then counts frames.
  bool track = false;
  double exposure_ms = 0.0;            // --exposure-ms: the track's (0 = the model's t_ref)
  double accel_psd_mm2_per_s3 = 0.0;   // --accel-psd: the filter's process noise (0 = default)
  double check_every_s = 0.0;          // --check-every: a bracket every S s (0 = none)

  bool IsValid(std::string* why) const;
};

// `irdist snap`: one frame to a PNG, the blob's position and a suggested roi_px.
struct SnapArgs {
  std::string rig = "virtual";
  std::string out;              // --out FILE.png
  bool force = false;           // --force: replace an existing FILE.png
  double exposure_ms = 8.0;     // --exposure-ms
  std::vector<double> at;       // --at (virtual rig only)
  double time_scale = 0.0;      // --time-scale (virtual rig; 0 = rig file's)

  bool IsValid(std::string* why) const;
};

// `irdist view`: a live window on the camera.
struct ViewArgs {
  std::string rig = "virtual";
  std::string model;            // --model: live estimate
  double exposure_ms = 8.0;     // --exposure-ms (without a model, and of the whole sensor)
  bool whole_sensor = false;    // --whole-sensor: start on the whole sensor (w toggles)
  std::vector<double> at;       // --at (virtual rig only)
  int frames = 0;               // --frames: quit after N frames (0 = until q / Esc)
  std::string screenshot;       // --screenshot FILE.png: save the last window image
  bool force = false;           // --force: replace an existing screenshot file
  double time_scale = 0.0;      // --time-scale (virtual rig; 0 = rig file's)

  bool IsValid(std::string* why) const;
};

struct CheckArgs {
  std::string recording;
};

struct PlanArgs {
  std::string recipe;
  int show_poses = 8;  // --poses: how many poses of the order to print (-1 = all)
  // --suggest: take probe frames on the recipe's rig and propose t_r, t_n and the current.
  bool suggest = false;
  std::string from_summary;  // --from: a validation's summary.yaml (its best_dt_ms)
  std::string out_dir;       // --out: the probe run's folder
  double time_scale = 0.0;   // --time-scale (virtual rig; 0 = rig file's)
  bool quiet = false;

  bool IsValid(std::string* why) const;
};

struct SimArgs {
  std::string rig = "virtual";  // rig name or rig file (kind: virtual)
  double time_scale = 0.0;      // --time-scale (0 = rig file's)

  bool IsValid(std::string* why) const;
};

// `irdist station`: put the station at a pose and current by hand (app/devices/station_cmd.h).
struct StationArgs {
  std::string rig = "virtual";      // rig name or rig file
  std::string action;               // move | current | off | home | status
  std::vector<double> values;       // move: SLIDE_MM PAN_DEG TILT_DEG; current: MA
  std::vector<std::string> ports;   // --port NAME=PATH (overrides the rig file / a running sim)

  bool IsValid(std::string* why) const;
};

// `irdist station-test PORT`: the conformance suite of docs/station-protocol.md against a board.
struct StationTestArgs {
  std::string port;
  int baud = 115200;

  bool IsValid(std::string* why) const;
};

// `irdist camera-test [CAMERA]`: a camera's features against irdist's needs
// (app/devices/camera_test.h).
struct CameraTestArgs {
  std::string camera;           // IP address, Aravis id or serial; empty = the running sim's
  std::string rig;  // --rig: its camera settings configure the camera; without CAMERA, whose
                    // running `irdist sim` camera to test (empty: virtual)
};

struct DevicesArgs {
  bool discover = false;  // --discover: GigE/USB camera discovery (broadcasts on every interface)
};


}  // namespace irdist
