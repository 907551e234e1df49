#pragma once
// What every irdist command receives: its output streams and its parsed flags, one Args struct per
// subcommand. A leaf header (no app/ include) so that each command family's header (run.h: live
// runs, offline.h: fit/playback/check, tools.h: sim/devices, cli.h: parsing and dispatch) declares
// its own commands without including another family's.

#include <iosfwd>
#include <string>

namespace irdist {

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
};

struct ValidateArgs {
  std::string recipe;
  std::string model;  // --model: model.yaml from a calibration
  std::string out_dir;
  std::string resume_dir;
  double time_scale = 0.0;
  bool quiet = false;
};

struct FitArgs {
  std::string recording;          // recording folder
  std::string out;                // --out: model file to write ("" = RECORDING/../model.yaml)
  bool recover_response = false;  // --recover-response: the camera's inverse response first
};

struct PlaybackArgs {
  std::string recording;
  std::string model;    // --model
  std::string out_dir;  // --out ("" = beside the recording)
  bool show = false;    // --show: step through the frames in an OpenCV window
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
};

struct SimArgs {
  std::string rig = "virtual";  // rig name or rig file (kind: virtual)
  double time_scale = 0.0;      // --time-scale (0 = rig file's)
};

struct DevicesArgs {
  bool discover = false;  // --discover: GigE/USB camera discovery (broadcasts on every interface)
};

}  // namespace irdist
