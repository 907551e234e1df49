#pragma once
// What `irdist check` says of a recording's images, beside its structure: the scene each bracket
// shows (estimator/scene.h through FrameFeatures): defect pixels, other blobs masked, a second
// source too close, an occluded disc, saturation and the ambient level. A report, not an error:
// a lab sees its scene's problems before it fits.

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace irdist {

class RecordingReader;

// One bracket's scene: the worst figure over its frames.
struct BracketScene {
  std::int64_t bracket = 0;
  int frames = 0;
  int no_blob = 0;                    // frames without a blob
  int defect_pixels = 0;              // most defect pixels replaced in one frame's window
  int other_blobs = 0;                // most other blobs masked in one frame
  int second_source = 0;              // frames with another source's light on the IRED's
  double second_source_gap_px = NAN;  // the smallest gap over those
  int occluded = 0;                   // frames whose disc is occluded
  double occluded_edge_pct = 0.0;     // the largest share of the edge affected
  int saturated = 0;                  // frames with saturated pixels
  double ambient_pct = 0.0;           // the largest background level, % of full scale
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
