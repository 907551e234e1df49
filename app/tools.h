#pragma once
// The smaller commands: `irdist sim` (run a virtual rig until Ctrl-C), `irdist devices` (what
// irdist can connect to), and playback's `--show` window.

#include <map>
#include <string>
#include <vector>

#include "app/cli.h"
#include "app/offline.h"
#include "app/summary.h"

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
// A state file's `key: value` lines (irdist sim writes `port.<device>: "<pty>"` for each station
// device, and `station_port`).
std::map<std::string, std::string> ReadFlatYaml(const std::string& path);

// An OpenCV window stepping through the recording's frames with the ROI, the ellipse and the
// bracket's estimate drawn (any key: next frame, q or Esc: quit). Throws CameraError-free
// irdist::Error (DisplayError) when no display is available.
void ShowPlayback(const RecordingReader& reader, const FeatureMap& features,
                  const std::vector<EstimateRow>& estimates);

class DisplayError : public Error {
 public:
  using Error::Error;
};

}  // namespace irdist
