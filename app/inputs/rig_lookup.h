#pragma once
// Finding a command's rig: the rig file a `--rig` value names, and the running sim (irdist sim)
// of that rig file, whose camera and station the live commands use instead of starting their own.

#include <iosfwd>
#include <optional>
#include <string>

#include "app/inputs/state_file.h"

namespace irdist {

// The rig file a `--rig` value names: a path, or a name in recipes/rigs/. Throws RecipeError.
std::string ResolveRig(const std::string& spec);
// The running sim of the rig file `rig_path` (the same file), or nullopt when none runs. Only the
// user's own live sims count (app/inputs/state_file.h LiveSims); every other state file is skipped
// with one warning on `warn`.
std::optional<RunningSim> FindRunningSim(const std::string& rig_path, std::ostream& warn);

}  // namespace irdist
