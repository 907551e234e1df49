#pragma once
// The per-user runtime state of `irdist sim`: its state file (what to connect to) in a private
// folder, created new and replaced whole, never through a planted link; and the readers' rule: a
// state file counts only when it is the user's own file, its process is a live `irdist sim` of
// the same user, and its ports are that user's pseudo-terminals. Anything else is skipped with
// one warning; reading never fails.

#include <iosfwd>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "base/check.h"

namespace irdist {

// The runtime folder cannot be made private. Names the folder and the fix.
class StateFileError : public Error {
 public:
  using Error::Error;
};

// The folder of the user's runtime state: $XDG_RUNTIME_DIR/irdist when XDG_RUNTIME_DIR names a
// folder, else irdist-<uid> in the temp folder ($TMPDIR or /tmp). Created 0700 and checked (the
// user's own folder, mode 700, not a symbolic link). Throws StateFileError.
std::string RuntimeStateDir();

// What a running `irdist sim` tells the other commands.
struct SimState {
  long pid = 0;
  std::string rig;  // the rig file, absolute
  std::string camera_id, camera_address, serial, station_port;
  double time_scale = 1.0;
  std::map<std::string, std::string> ports;  // station.devices name -> pty
  std::string trajectory_csv;  // the station's trajectory file (sim/trajectory_file.h), or ""
};

// The state file's YAML (yaml-cpp's emitter): pid, rig, camera_id, camera_address, serial,
// station_port, time_scale, `port.<device>` for each device and `trajectory_csv` when logged.
std::string SimStateYaml(const SimState& state);

// Writes the state file irdist-sim-<pid>.yaml into RuntimeStateDir(), created new through a
// temporary file and a rename. Returns its path. Throws StateFileError.
std::string WriteSimState(const SimState& state);

// A state file as the readers see it: its pid and `key: value` pairs (port.<device> for each
// station device).
struct RunningSim {
  long pid = 0;
  std::string state_path;
  std::map<std::string, std::string> values;
};

// Every state file in RuntimeStateDir() that passes the readers' rule. Each file skipped for
// another reason than a dead process (not the user's, not a state file, a process that is not
// an `irdist sim` of the user, a port that is not the user's pty) gets one line on `warn`.
std::vector<RunningSim> LiveSims(std::ostream& warn);

// Whether process `pid` is a live `irdist sim` of the calling user (/proc: its owner, argv[0]
// named irdist and its command sim).
bool IsOwnIrdistSim(long pid);

// Why `port` is not a pseudo-terminal of the calling user ("" when it is one).
std::string NotOwnPty(const std::string& port);

}  // namespace irdist
