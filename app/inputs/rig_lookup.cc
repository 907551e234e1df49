#include "app/inputs/rig_lookup.h"

#include <filesystem>

#include "app/inputs/errors.h"
#include "app/inputs/recipe.h"

namespace irdist {

namespace fs = std::filesystem;

std::string ResolveRig(const std::string& spec) {
  if (fs::exists(spec)) return spec;
  std::string found = FindRigFile(spec, fs::current_path().string());
  if (found.empty()) {
    throw RecipeError(spec, 0, 0,
                      "no such rig: give a rig file (recipes/rigs/virtual.yaml) or the name of "
                      "one in recipes/rigs/ (e.g. virtual).");
  }
  return found;
}

std::optional<RunningSim> FindRunningSim(const std::string& rig_path, std::ostream& warn) {
  for (RunningSim& sim : LiveSims(warn)) {
    const auto rig = sim.values.find("rig");
    std::error_code same_error;
    if (rig != sim.values.end() && fs::equivalent(rig->second, rig_path, same_error)) return sim;
  }
  return std::nullopt;
}

}  // namespace irdist
