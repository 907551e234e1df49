#pragma once
// "Accepted implies in the table": what the rig and recipe fuzz targets assert of every input the
// readers accept, against base/bounds.h (the table the readers check with).

#include "app/inputs/recipe.h"
#include "app/inputs/rig.h"
#include "app/inputs/track_recipe.h"
#include "base/bounds.h"

namespace irdist::fuzz {

inline bool RigInBounds(const Rig& rig) {
  const CameraIntrinsics& k = rig.camera.intrinsics;
  if (!k.known) return true;
  if (!bounds::kFocalPx.Contains(k.fx_px) || !bounds::kFocalPx.Contains(k.fy_px)) return false;
  if (!bounds::kSensorPx.Contains(k.cx_px) || !bounds::kSensorPx.Contains(k.cy_px)) return false;
  if (k.in_roi_px && rig.camera.roi_width > 0 &&
      (k.cx_px > rig.camera.roi_width || k.cy_px > rig.camera.roi_height)) {
    return false;  // the principal point lies inside the pixels it is stated in
  }
  for (size_t i = 0; i < k.distortion.size(); ++i) {
    const bool tangential = i == 2 || i == 3;
    const Bound& bound = tangential ? bounds::kTangentialDistortion : bounds::kRadialDistortion;
    if (!bound.Contains(k.distortion[i])) return false;
  }
  return true;
}

inline bool RecipeInBounds(const Recipe& recipe) {
  const BracketSpec& bracket = recipe.sweep.bracket;
  if (!bounds::kExposureMs.Contains(bracket.t_ref_ms)) return false;
  for (double t_ms : bracket.t_meas_ms) {
    if (!bounds::kExposureMs.Contains(t_ms) || !(t_ms > bracket.t_ref_ms)) return false;
  }
  return RigInBounds(recipe.rig);
}

// A track recipe: every position inside the rig's limits, every moving axis's speed in its bound.
inline bool TrackRecipeInBounds(const TrackRecipe& recipe) {
  const StationLimits& limits = recipe.rig.station.limits;
  if (!bounds::kCurrentMa.Contains(recipe.bias_ma) || !limits.bias_ma.Contains(recipe.bias_ma)) {
    return false;
  }
  if (recipe.segments.empty()) return false;
  for (const TrackSegment& s : recipe.segments) {
    for (double mm : {s.slide_from_mm, s.slide_to_mm}) {
      if (!limits.slide_mm.Contains(mm)) return false;
    }
    for (double deg : {s.pan_from_deg, s.pan_to_deg}) {
      if (!limits.pan_deg.Contains(deg)) return false;
    }
    if (s.slide_from_mm != s.slide_to_mm && !bounds::kSlideSpeedMmS.Contains(s.speed_mm_s)) {
      return false;
    }
    if (s.pan_from_deg != s.pan_to_deg && !bounds::kAngularSpeedDegS.Contains(s.pan_speed_deg_s)) {
      return false;
    }
  }
  return RigInBounds(recipe.rig);
}

}  // namespace irdist::fuzz
