#pragma once
// What `irdist check` says of a recording's images, beside its structure: the scene each bracket
// shows (estimator/scene.h through FrameFeatures): defect pixels, other blobs masked, a second
// source too close, an occluded disc, saturation and the ambient level. A report, not an error:
// a lab sees its scene's problems before it fits.

#include <cstdint>
#include <string>
#include <vector>

#include "app/processing/estimate_flags.h"

namespace irdist {

class RecordingReader;

// One bracket's scene: the worst figure over its frames (the flags' own aggregate).
struct BracketScene {
  std::int64_t bracket = 0;
  SceneFigures figures;
  // Anything a lab should look at (not defects or other blobs alone, which are measured through).
  bool Suspect() const;
};

struct SceneCheck {
  std::vector<BracketScene> brackets;
  // A table of the brackets with findings and a totals line.
  std::string BriefReport() const;
};

// The scene of every bracket of `reader` (each frame's features with the default options).
SceneCheck CheckScene(const RecordingReader& reader);

}  // namespace irdist
