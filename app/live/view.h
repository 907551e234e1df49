#pragma once
// Seeing the camera: `irdist snap` (one frame to a PNG, the blob's position and a suggested
// roi_px) and `irdist view` (a live window: image, blob window, ellipse, signal and saturation,
// the live estimate with --model; keys on screen). Both work on a virtual rig (started here).

#include "app/inputs/command_args.h"

namespace irdist {

void RunSnap(const SnapArgs& args, CommandIo io);
// Throws DisplayError without a display.
void RunView(const ViewArgs& args, CommandIo io);

}  // namespace irdist
