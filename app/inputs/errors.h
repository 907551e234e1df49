#pragma once
// The app's typed errors. main.cc maps them to exit codes: RecipeError and every other
// irdist::Error -> 1 (a failed run), UsageError -> 2, InterruptedError ->
// 130.

#include <string>
#include <utility>

#include "base/check.h"
#include "base/input_error.h"

namespace irdist {

// A recipe or rig file that cannot be used (base/input_error.h): file:line:column, what is wrong
// and what would be valid. Thrown before anything moves.
using RecipeError = InputError;

// The command line is wrong (unknown command, missing or bad argument). Exit code 2.
class UsageError : public Error {
 public:
  using Error::Error;
};

// A run stopped by SIGINT/SIGTERM after finishing the bracket in flight: the recording is closed as
// cut and the message says how to resume. Exit code 130.
class InterruptedError : public Error {
 public:
  using Error::Error;
};

// A run folder that cannot be used (a recording already there, nothing to resume). Exit code 1.
class RunFolderError : public Error {
 public:
  using Error::Error;
};

// `plan --suggest` found no exposures that keep the nearest pose unsaturated and the farthest
// above the noise. Exit code 1.
class SuggestError : public Error {
 public:
  using Error::Error;
};

// A check that ran but found problems (e.g. `irdist check` on a damaged recording). Exit code 1.
class CheckFailedError : public Error {
 public:
  using Error::Error;
};

}  // namespace irdist
