#pragma once
// Seeing the camera: `irdist view` (a live window: image, blob window, ellipse, signal and
// saturation, the live estimate with --model; keys on screen). Works on a virtual rig (started
// here). `irdist snap` is in app/live/snap_command.h.

#include "app/inputs/command_args.h"

namespace irdist {

// Throws DisplayError without a display.
void RunView(const ViewArgs& args, CommandIo io);

}  // namespace irdist
