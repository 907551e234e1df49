#pragma once
// `irdist sim`: runs a virtual rig until Ctrl-C, for the other commands to find.

#include "app/inputs/command_args.h"
#include "app/inputs/errors.h"

namespace irdist {

// Starts the virtual rig, prints `camera: <id> <address> serial <serial>` and `station: <pty>`,
// writes a state file (app/inputs/state_file.h: irdist-sim-<pid>.yaml in the user's private runtime
// folder), logs the station's trajectory to irdist-sim-<pid>-trajectory.csv beside it (printed as
// `trajectory:`, and the state file's `trajectory_csv`) and runs until SIGINT/SIGTERM; then stops
// the rig and removes the state file and the trajectory file. The other commands find it with
// FindRunningSim (app/inputs/rig_lookup.h).
void RunSim(const SimArgs& args, CommandIo io);

}  // namespace irdist
