#pragma once
// The smaller commands: `irdist sim` (run a virtual rig until Ctrl-C) and `irdist devices` (what
// irdist can connect to). Playback's `--show` window is in app/display/show.h.

#include <iosfwd>
#include <optional>
#include <string>

#include "app/inputs/command_args.h"
#include "app/inputs/errors.h"
#include "app/inputs/state_file.h"

namespace irdist {

// Starts the virtual rig, prints `camera: <id> <address> serial <serial>` and `station: <pty>`,
// writes a state file (app/inputs/state_file.h: irdist-sim-<pid>.yaml in the user's private runtime
// folder), logs the station's trajectory to irdist-sim-<pid>-trajectory.csv beside it (printed as
// `trajectory:`, and the state file's `trajectory_csv`) and runs until SIGINT/SIGTERM; then stops
// the rig and removes the state file and the trajectory file.
void RunSim(const SimArgs& args, CommandIo io);

// Lists running virtual rigs (their state files), serial ports (/dev/ttyUSB*, /dev/ttyACM*) and,
// with --discover only, cameras found by Aravis discovery.
void RunDevices(const DevicesArgs& args, CommandIo io);

// The rig file a `--rig` value names: a path, or a name in recipes/rigs/. Throws RecipeError.
std::string ResolveRig(const std::string& spec);
// The running sim of the rig file `rig_path` (the same file), or nullopt when none runs. Only the
// user's own live sims count (app/inputs/state_file.h LiveSims); every other state file is skipped
// with one warning on `warn`.
std::optional<RunningSim> FindRunningSim(const std::string& rig_path, std::ostream& warn);

}  // namespace irdist
