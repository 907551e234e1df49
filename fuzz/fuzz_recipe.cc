// libFuzzer target: the recipe and rig-file parsers (app/inputs/recipe.h, app/inputs/rig.h) on one
// input, read both as a rig file and as a recipe (whose rig is looked up in the shipped
// recipes/rigs/), and a recipe that parses is planned (station/plan.h: grid, random draws, axis
// order, durations). An accepted input lies inside the bounds table (fuzz/in_bounds.h). Every
// refusal must be an InputError (RecipeError) with the file named; a hang is a libFuzzer timeout.
#include <cstddef>
#include <cstdint>
#include <string>

#include "app/inputs/errors.h"
#include "app/inputs/recipe.h"
#include "app/inputs/rig.h"
#include "fuzz/in_bounds.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    if (!irdist::fuzz::RigInBounds(irdist::ParseRig(text, "fuzz-rig.yaml"))) __builtin_trap();
  } catch (const irdist::InputError& error) {
    if (error.File() != "fuzz-rig.yaml") __builtin_trap();
  }
  try {
    const irdist::Recipe recipe =
        irdist::ParseRecipe(text, "fuzz-recipe.yaml", IRDIST_SOURCE_DIR "/recipes");
    if (!irdist::fuzz::RecipeInBounds(recipe)) __builtin_trap();
    irdist::PlanRecipe(recipe);
  } catch (const irdist::InputError& error) {
    if (error.File().empty()) __builtin_trap();
  }
  return 0;
}
