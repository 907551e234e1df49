#pragma once
// The smaller commands: `irdist sim` (run a virtual rig until Ctrl-C) and `irdist devices` (what
// irdist can connect to). Playback's `--show` window is in app/show.h.

#include <map>
#include <optional>
#include <string>

#include "app/command_args.h"
#include "app/errors.h"

namespace irdist {

// Starts the virtual rig, prints `camera: <id> <address> serial <serial>` and `station: <pty>`,
// writes a state file ($XDG_RUNTIME_DIR or /tmp, irdist-sim-<pid>.yaml) and runs until
// SIGINT/SIGTERM; then stops the rig and removes the state file.
void RunSim(const SimArgs& args, CommandIo io);

// Lists running virtual rigs (their state files), serial ports (/dev/ttyUSB*, /dev/ttyACM*) and,
// with --discover only, cameras found by Aravis discovery.
void RunDevices(const DevicesArgs& args, CommandIo io);

// Folder of the virtual rigs' state files.
std::string SimStateDir();
// The rig file a `--rig` value names: a path, or a name in recipes/rigs/. Throws RecipeError.
std::string ResolveRig(const std::string& spec);
// A running `irdist sim` of a rig file: its pid and state file's values (camera_address, serial,
// time_scale, station_port, port.<device>, ...).
struct RunningSim {
  long pid = 0;
  std::string state_path;
  std::map<std::string, std::string> values;
};
// The running sim of the rig file `rig_path` (the same file), or nullopt when none runs (state
// files of rigs whose process is gone are skipped).
std::optional<RunningSim> FindRunningSim(const std::string& rig_path);
// A state file's `key: value` lines (irdist sim writes `port.<device>: "<pty>"` for each station
// device, and `station_port`).
std::map<std::string, std::string> ReadFlatYaml(const std::string& path);

}  // namespace irdist
