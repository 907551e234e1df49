#pragma once
// `irdist fit RECORDING`: the calibration of calibrate, offline from a recording already made
// (model.yaml, features.csv and report/ beside it). The processing is the live runs' own
// (app/processing/), so the same recording gives byte-identical files.

#include "app/inputs/command_args.h"
#include "app/inputs/errors.h"

namespace irdist {

// Throws RecordingError, CheckFailedError (a recording with errors), RunFolderError (results
// that exist without --force, a link, a live writer), ModelFileError, ...
void RunFit(const FitArgs& args, CommandIo io);

}  // namespace irdist
