#pragma once
// `irdist snap`: one frame of the rig's camera to a PNG (and an 8-bit preview beside it), the
// blob's position and a suggested roi_px. Works on a virtual rig (started here).

#include "app/inputs/command_args.h"

namespace irdist {

// Throws UsageError (--out not a .png), RunFolderError (an existing file without --force, a link,
// a missing folder; all before the camera starts) and CameraError.
void RunSnap(const SnapArgs& args, CommandIo io);

}  // namespace irdist
