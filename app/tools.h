#pragma once
// The smaller commands: `irdist sim` (run a virtual rig until Ctrl-C), `irdist devices` (what
// irdist can connect to), and playback's `--show` window.

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

// An OpenCV window stepping through the recording's frames with the ROI, the ellipse and the
// bracket's estimate drawn (any key: next frame, q or Esc: quit). Throws CameraError-free
// irdist::Error (DisplayError) when no display is available.
void ShowPlayback(const RecordingReader& reader, const FeatureMap& features,
                  const std::vector<EstimateRow>& estimates);

class DisplayError : public Error {
 public:
  using Error::Error;
};

// Throws DisplayError (naming `what`) when neither DISPLAY nor WAYLAND_DISPLAY is set.
void RequireDisplay(const std::string& what);
// cv::namedWindow; throws DisplayError when OpenCV cannot open it.
void OpenWindow(const std::string& window, const std::string& what);
// A frame for display: gray scaled to 8 bits, the features' window (green) and ellipse (red),
// `lines` of text at the top left.
cv::Mat FrameOverlay(const cv::Mat& image, int bit_depth, const Features* features,
                     const std::vector<std::string>& lines);

}  // namespace irdist
