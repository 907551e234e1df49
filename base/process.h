#pragma once
// Running an external program without a shell: an argument vector handed to posix_spawn, a
// working folder, standard output and error sent to files, the exit status checked. No word of
// a path is ever interpreted: quotes, spaces, `$`, `;` and `'` reach the program as they are.

#include <string>
#include <vector>

#include "base/check.h"

namespace irdist {

// The program could not be started, or waiting for it failed.
class ProcessError : public Error {
 public:
  using Error::Error;
};

struct ProcessSpec {
  std::vector<std::string> argv;  // argv[0]: a path, or a name searched on PATH
  std::string working_dir;        // "" = the caller's current folder
  std::string stdout_path;        // "" = /dev/null; created or truncated
  std::string stderr_path;        // "" = /dev/null; created or truncated
};

struct ProcessResult {
  bool exited = false;  // ended by exit (not by a signal)
  int exit_code = -1;   // when exited
  int signal = 0;       // when killed by a signal
  bool Succeeded() const { return exited && exit_code == 0; }
};

// The absolute path of `name` on PATH (an executable regular file), or "" when there is none.
// A name with a '/' is returned as it is when it is executable.
std::string FindProgram(const std::string& name);

// Starts the program, waits for it and returns how it ended. Relative stdout/stderr paths are
// taken relative to the caller's current folder (not working_dir). Throws ProcessError naming
// the program when it cannot be started (not found, working folder missing, output not writable).
ProcessResult RunProgram(const ProcessSpec& spec);

}  // namespace irdist
