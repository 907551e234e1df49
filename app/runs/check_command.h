#pragma once
// `irdist check PATH`: a recording's integrity (its structure, then the scene its images show) or
// an estimates.csv's (every row read, a torn last line noted). Reads only; writes nothing.

#include "app/inputs/command_args.h"
#include "app/inputs/errors.h"

namespace irdist {

// Prints the check's report; throws CheckFailedError when the recording has errors or the
// estimates.csv cannot be read.
void RunCheck(const CheckArgs& args, CommandIo io);

}  // namespace irdist
