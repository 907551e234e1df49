#pragma once
// `irdist station` (put the station at a pose and current by hand, with the same Station code as
// the sweep) and `irdist station-test` (the conformance suite of docs/station-protocol.md).

#include "app/inputs/command_args.h"
#include "app/inputs/errors.h"

namespace irdist {

// move SLIDE_MM PAN_DEG TILT_DEG | current MA | off | home | status, on the rig's station. On a
// virtual rig the ports come from the running `irdist sim` of that rig (its state file) or from
// --port NAME=PATH. The IRED stays at the set current when the command ends (`off` switches it
// off). Throws UsageError, RecipeError (limits), DeviceError, LinkError, StationNotReadyError.
void RunStation(const StationArgs& args, CommandIo io);

// Runs the conformance suite against the board on args.port and prints the table; throws
// CheckFailedError when a check fails.
void RunStationTest(const StationTestArgs& args, CommandIo io);

}  // namespace irdist
