#pragma once
// Recipes (recipes/*.yaml): what a run sweeps, how each pose is bracketed, which rig it runs on,
// where it writes and what it does after recording. Loading checks everything (unknown keys, wrong
// types, values outside the rig's station.limits, empty axes, ranges that miss their stop) and
// throws RecipeError naming file:line:column and what would be valid, before anything moves.
// docs/recipes.md is the reference of every key.

#include <string>

#include "app/inputs/errors.h"
#include "app/inputs/rig.h"
#include "station/plan.h"

namespace irdist {

// What a run does once the frames are recorded.
enum class AfterRecording {
  kNone,      // record only
  kFit,       // calibration: fit the models, write model.yaml
  kEstimate,  // validation: estimate every bracket, write estimates.csv and summary.yaml
};

std::string AfterRecordingName(AfterRecording after);  // "none", "fit", "estimate"

// calibration.camera_response: how the calibration's fit treats the camera's response.
enum class CameraResponse {
  kLinear,   // the camera is taken as linear (default; the paper's assumption)
  kRecover,  // the inverse response is recovered from the recorded brackets and linearises every
             // pixel before the features (model.yaml: features.response_scope all_pixels)
};

std::string CameraResponseName(CameraResponse response);  // "linear", "recover"

struct Recipe {
  std::string path;         // the recipe file
  std::string name;         // `name:`, defaults to the file's stem
  std::string description;  // `description:`
  std::string rig_path;     // resolved rig file
  Rig rig;                  // loaded rig (camera:, station:)
  std::string output_dir;   // `output:`, defaults to runs/<name>; relative to the working dir
  AfterRecording after = AfterRecording::kNone;
  CameraResponse camera_response = CameraResponse::kLinear;  // `calibration: {camera_response:}`
  SweepSpec sweep;     // axes (expanded), order, serpentine, bracket, settle
  MotionModel motion;  // the rig's timing model (station.motion + camera.readout_ms)
};

// Loads a recipe and its rig. Throws RecipeError.
Recipe LoadRecipe(const std::string& path);

// Same, from text. `file` names the recipe in errors; `base_dir` is where a rig given as a
// relative path is looked for (normally the recipe's folder).
Recipe ParseRecipe(const std::string& text, const std::string& file, const std::string& base_dir);

// Only the `calibration:` section of a recipe's text (e.g. the recipe a recording was made with,
// RecordingHeader::recipe_text), without loading its rig. Throws RecipeError naming file:line.
CameraResponse CameraResponseOfRecipeText(const std::string& text, const std::string& file);

// The folder of the shipped recipes and rig files: <prefix>/share/irdist/recipes beside an
// installed irdist (<prefix>/bin/irdist, found from the running program's real path, through any
// symlink), else recipes/ of the source tree this build came from.
std::string ShippedRecipesDir();

// Where `rig: SPEC` points: a name ("virtual") is looked up as rigs/NAME.yaml beside the recipe,
// then in ShippedRecipesDir()/rigs/; a path (containing '/' or ending in .yaml)
// is taken relative to base_dir. Returns "" when no file exists.
std::string FindRigFile(const std::string& spec, const std::string& base_dir);

// The recipe's sweep plan (poses, bracket, duration estimate) on its rig's motion model.
Plan PlanRecipe(const Recipe& recipe);

}  // namespace irdist
