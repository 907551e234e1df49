#pragma once
// `irdist devices`: what irdist can connect to.

#include "app/inputs/command_args.h"
#include "app/inputs/errors.h"

namespace irdist {

// Lists running virtual rigs (their state files), serial ports (/dev/ttyUSB*, /dev/ttyACM*) and,
// with --discover only, cameras found by Aravis discovery.
void RunDevices(const DevicesArgs& args, CommandIo io);

}  // namespace irdist
