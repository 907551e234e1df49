#pragma once
// The irdist command line: a dispatch table of subcommands (calibrate, validate, fit, playback,
// check, plan, sim, devices). Each subcommand parses into an Args struct and calls its handler in
// Handlers; an empty handler means the modules behind it are not integrated in this build, and
// the command says so (NotAvailableError, exit code 2). Integrating a command = filling its
// handler in DefaultHandlers() (app/cli/cli.cc).

#include <functional>
#include <iosfwd>
#include <string>
#include <vector>

#include "app/inputs/command_args.h"
#include "app/inputs/errors.h"

namespace irdist {

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
  std::function<void(const MeasureArgs&, CommandIo)> measure;
  std::function<void(const SnapArgs&, CommandIo)> snap;
  std::function<void(const ViewArgs&, CommandIo)> view;
  std::function<void(const StationArgs&, CommandIo)> station;
  std::function<void(const StationTestArgs&, CommandIo)> station_test;
  std::function<void(const CameraTestArgs&, CommandIo)> camera_test;
};

// The handlers of this build: every command (app/runs/run.h, app/runs/run_suggest.h,
// app/runs/offline.h, app/devices/tools.h).
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
