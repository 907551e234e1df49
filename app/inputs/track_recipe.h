#pragma once
// Track recipes (`kind: track`, e.g. recipes/track-slide.yaml; docs/recipes.md "Track recipes"):
// the station moves the slide (and the pan) through a profile of segments, each at its own
// cruise speed, while `irdist validate` tracks every frame (docs/measure.md "Tracking"). The
// loader is the strict one of every recipe: unknown keys, wrong types, a number outside its
// bound or the rig's station.limits, a segment that moves nothing, are RecipeError at
// file:line:column with the fix, before anything moves. The sweep recipes keep their own parser
// (app/inputs/recipe.h); RecipeKindOf tells the two apart.

#include <string>
#include <vector>

#include "app/inputs/errors.h"
#include "app/inputs/rig.h"

namespace irdist {

// A recipe's `kind:`: "sweep" (absent: the calibration and validation sweeps) or "track".
// Throws RecipeError on an unreadable file or another kind.
std::string RecipeKindOf(const std::string& path);
std::string RecipeKindOfText(const std::string& text, const std::string& file);

// One segment of the profile: the station goes to (slide_from_mm, pan_from_deg) at its own
// speed, waits the recipe's settle, then moves to (slide_to_mm, pan_to_deg), the slide cruising
// at speed_mm_s and the pan at pan_speed_deg_s.
struct TrackSegment {
  double slide_from_mm = 0.0, slide_to_mm = 0.0, speed_mm_s = 0.0;
  double pan_from_deg = 0.0, pan_to_deg = 0.0, pan_speed_deg_s = 0.0;  // 0: the pan stands
  int line = 0;  // 1-based line of the segment in the recipe
};

struct TrackRecipe {
  std::string path, name, description;
  std::string rig_path;
  Rig rig;
  std::string output_dir;  // `output:`, defaults to runs/<name>
  double bias_ma = 0.0;    // track.bias_ma: the IRED's current through the run
  double tilt_deg = 0.0;   // track.tilt_deg
  double exposure_ms = 0.0;           // track.exposure_ms (0: the model's reference exposure)
  double accel_psd_mm2_per_s3 = 0.0;  // track.accel_psd_mm2_per_s3 (0: the rig's or default)
  double settle_ms = 500.0;  // track.settle_ms: tracked at rest before each segment's move
  double after_ms = 500.0;   // track.after_ms: tracked at rest after the last segment
  // track.truth_sd_mm: on a rig without the virtual rig's trajectory, the truth is the commanded
  // profile; its stated standard uncertainty (following error, start time x speed).
  double truth_sd_mm = 2.0;
  std::vector<TrackSegment> segments;
};

// Loads a track recipe and its rig. Throws RecipeError.
TrackRecipe LoadTrackRecipe(const std::string& path);
// Same, from text (`file` names it in errors; a relative rig path is looked for in base_dir).
TrackRecipe ParseTrackRecipe(const std::string& text, const std::string& file,
                             const std::string& base_dir);

}  // namespace irdist
