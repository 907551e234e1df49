#pragma once
// `irdist check`: what is wrong with a recording, by file and line (bad rows, missing, damaged or
// replaced frames, gaps, leftovers, a header that contradicts its frames), without throwing on
// what it finds. The checks beyond the format are acquisition/recording_integrity.h's.

#include <string>

#include "acquisition/recording_types.h"

namespace irdist {

// Checks a recording without throwing on what it finds (throws RecordingError only when `dir` is
// not a recording at all). Loads every PNG to verify it.
RecordingCheck CheckRecording(const std::string& dir);

}  // namespace irdist
