#pragma once
// `irdist playback RECORDING`: a recording's features (features.csv) and, with a model, the
// estimates of validate (estimates.csv; with ground truth summary.yaml and report/), offline;
// --show opens the playback window. The processing is the live runs' own (app/processing/), so
// the same recording gives byte-identical files.

#include "app/inputs/command_args.h"
#include "app/inputs/errors.h"

namespace irdist {

// Throws RecordingError, CheckFailedError (a recording with errors), RunFolderError (results
// that exist without --force, a link, a live writer), ModelFileError, ...
void RunPlayback(const PlaybackArgs& args, CommandIo io);

}  // namespace irdist
