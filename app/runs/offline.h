#pragma once
// The offline commands, on a recording already made: `irdist fit` (the calibration of calibrate),
// `irdist playback` (features and, with a model, the estimates of validate; --show) and
// `irdist check` (a recording's or an estimates.csv's integrity). The processing itself is the
// live runs' own (app/processing/), so the same recording gives byte-identical files.

#include "app/inputs/command_args.h"
#include "app/inputs/errors.h"

namespace irdist {

// They throw RecordingError, ModelFileError, ...; RunCheck prints the check's report and throws
// CheckFailedError when the recording has errors.
void RunFit(const FitArgs& args, CommandIo io);
void RunPlayback(const PlaybackArgs& args, CommandIo io);
void RunCheck(const CheckArgs& args, CommandIo io);

}  // namespace irdist
