// libFuzzer target: the recipe parsers (app/inputs/recipe.h; a `kind: track` recipe's,
// app/inputs/track_recipe.h), and a sweep recipe that parses is planned (station/plan.h: grid,
// random draws, axis order, durations). An accepted recipe lies inside the
// bounds table (fuzz/in_bounds.h). Every refusal must be an InputError (RecipeError) with the file
// named; a hang is a libFuzzer timeout.
// A recipe's rig name is looked up in fuzz/recipe_rigs/rigs/ first: the shipped rigs without their
// comments and virtual: sections, which the recipe never reads (a 5-8 kB rig parsed again for every
// input took a fifth of the target's time). The rig file's own parser is fuzz_rig's.
#include <cstddef>
#include <cstdint>
#include <string>

#include "app/inputs/errors.h"
#include "app/inputs/recipe.h"
#include "app/inputs/track_recipe.h"
#include "fuzz/in_bounds.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const char* const rigs = IRDIST_SOURCE_DIR "/fuzz/recipe_rigs";
    if (irdist::RecipeKindOfText(text, "fuzz-recipe.yaml") == "track") {
      const irdist::TrackRecipe track = irdist::ParseTrackRecipe(text, "fuzz-recipe.yaml", rigs);
      if (!irdist::fuzz::TrackRecipeInBounds(track)) __builtin_trap();
      return 0;
    }
    const irdist::Recipe recipe = irdist::ParseRecipe(text, "fuzz-recipe.yaml", rigs);
    if (!irdist::fuzz::RecipeInBounds(recipe)) __builtin_trap();
    irdist::PlanRecipe(recipe);
  } catch (const irdist::InputError& error) {
    if (error.File().empty()) __builtin_trap();
  }
  return 0;
}
