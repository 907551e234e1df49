#pragma once
// The irdist command line, the top of the house: one table of subcommands (calibrate, validate,
// fit, playback, check, plan, sim, devices, measure, snap, view, station, station-test,
// camera-test), each entry its name, help, flags and handler (cli.cc, kCommands). Each
// subcommand parses its flags into an Args struct and calls its handler in Handlers, the
// engine's entry point in the folder below (DefaultHandlers); a test may give other handlers to
// see what a command line parses into.

#include <functional>
#include <iosfwd>
#include <string>
#include <vector>

#include "app/inputs/command_args.h"
#include "app/inputs/errors.h"

namespace irdist {

// One handler per subcommand. A handler reports results on io.out, throws irdist::Error
// subclasses on failure (main.cc maps them to exit codes) and returns normally on success.
template <typename Args>
using CommandHandler = std::function<void(const Args&, CommandIo)>;
// The slots the command table's entries name (a test fills its own).
struct Handlers {
  CommandHandler<CalibrateArgs> calibrate;
  CommandHandler<ValidateArgs> validate;
  CommandHandler<FitArgs> fit;
  CommandHandler<PlaybackArgs> playback;
  CommandHandler<CheckArgs> check;
  CommandHandler<PlanArgs> plan;
  CommandHandler<SimArgs> sim;
  CommandHandler<DevicesArgs> devices;
  CommandHandler<MeasureArgs> measure;
  CommandHandler<SnapArgs> snap;
  CommandHandler<ViewArgs> view;
  CommandHandler<StationArgs> station;
  CommandHandler<StationTestArgs> station_test;
  CommandHandler<CameraTestArgs> camera_test;
};

// The handlers of this build, from the table: every command's entry point (app/runs/run.h,
// app/runs/plan_command.h, app/runs/fit_command.h, app/devices/sim_command.h, app/live/measure.h,
// ...).
Handlers DefaultHandlers();

// The table's commands whose slot in `handlers` is empty; those whose help is empty.
std::vector<std::string> CommandsWithoutHandler(const Handlers& handlers);
std::vector<std::string> CommandsWithoutHelp();

// Names of the subcommands, in help order.
std::vector<std::string> SubcommandNames();

// Parses argv (argv[0] is the program name) and runs the chosen subcommand. Returns the exit
// code of a successful run (0; also for --help). Throws UsageError for a bad command line and
// whatever the handler throws (RecipeError, ...); CheckError for a command without a handler.
int RunIrdist(int argc, const char* const* argv, CommandIo io,
              const Handlers& handlers = DefaultHandlers());

}  // namespace irdist
