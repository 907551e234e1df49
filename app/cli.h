#pragma once
// The irdist command line: a dispatch table of subcommands (calibrate, validate, fit, playback,
// check, plan, sim, devices). Each subcommand parses into an Args struct and calls its handler in
// Handlers; an empty handler means the modules behind it are not integrated in this build, and
// the command says so (NotAvailableError, exit code 2). Integrating a command = filling its
// handler in DefaultHandlers() (app/cli.cc).

#include <functional>
#include <iosfwd>
#include <string>
#include <vector>

#include "app/errors.h"

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
  std::string recording;  // recording folder
  std::string out;        // --out: model file to write ("" = RECORDING/../model.yaml)
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

// `irdist station --rig RIG ACTION [VALUES]`: drive the station by hand (app/station_cmd.cc).
struct StationArgs {
  std::string rig = "virtual";      // rig name or rig file
  std::string action;               // move | current | off | home | status
  std::vector<double> values;       // move: SLIDE_MM PAN_DEG TILT_DEG; current: MA
  std::vector<std::string> ports;   // --port NAME=PATH (overrides the rig file / a running sim)
};

// `irdist station-test PORT`: the conformance suite of docs/station-protocol.md against a board.
struct StationTestArgs {
  std::string port;
  int baud = 115200;
};

struct DevicesArgs {
  bool discover = false;  // --discover: GigE/USB camera discovery (broadcasts on every interface)
};

// One handler per subcommand. A handler reports results on io.out, throws irdist::Error
// subclasses on failure (main.cc maps them to exit codes) and returns normally on success.
struct Handlers {
  std::function<void(const CalibrateArgs&, CommandIo)> calibrate;
  std::function<void(const ValidateArgs&, CommandIo)> validate;
  std::function<void(const FitArgs&, CommandIo)> fit;
  std::function<void(const PlaybackArgs&, CommandIo)> playback;
  std::function<void(const CheckArgs&, CommandIo)> check;
  std::function<void(const PlanArgs&, CommandIo)> plan;
  std::function<void(const SimArgs&, CommandIo)> sim;
  std::function<void(const DevicesArgs&, CommandIo)> devices;
  std::function<void(const StationArgs&, CommandIo)> station;
  std::function<void(const StationTestArgs&, CommandIo)> station_test;
};

// The handlers of this build: every command (app/run.h, app/tools.h).
Handlers DefaultHandlers();

// Names of the subcommands, in help order.
std::vector<std::string> SubcommandNames();

// `irdist plan`: loads the recipe and prints grid, order, counts and the duration estimate.
void RunPlan(const PlanArgs& args, CommandIo io);

// Parses argv (argv[0] is the program name) and runs the chosen subcommand. Returns the exit
// code of a successful run (0; also for --help). Throws UsageError for a bad command line,
// NotAvailableError for a command whose modules are not integrated, and whatever the handler
// throws (RecipeError, ...).
int RunIrdist(int argc, const char* const* argv, CommandIo io,
              const Handlers& handlers = DefaultHandlers());

}  // namespace irdist
