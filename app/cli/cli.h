#pragma once
// The irdist command line, the top of the house: one table of subcommands (calibrate, validate,
// fit, playback, check, plan, sim, devices, measure, snap, view, station, station-test,
// camera-test). Each subcommand parses its flags into an Args struct and calls its handler in
// Handlers, the engine's entry point in the folder below (DefaultHandlers); a test may give
// other handlers to see what a command line parses into.

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

// The handlers of this build: every command (app/runs/run.h, app/runs/plan_command.h,
// app/runs/offline.h, app/devices/tools.h, app/live/measure.h, ...).
Handlers DefaultHandlers();

// Names of the subcommands, in help order.
std::vector<std::string> SubcommandNames();

// Parses argv (argv[0] is the program name) and runs the chosen subcommand. Returns the exit
// code of a successful run (0; also for --help). Throws UsageError for a bad command line and
// whatever the handler throws (RecipeError, ...); CheckError for a command without a handler.
int RunIrdist(int argc, const char* const* argv, CommandIo io,
              const Handlers& handlers = DefaultHandlers());

}  // namespace irdist
