#pragma once
// Defect pixels of the virtual sensor (docs/virtual-rig.md "A lab's scene"): hot pixels, whose own
// dark current adds a fixed rate of electrons per second (so their reading grows linearly with the
// exposure, shot noise included), and stuck pixels, whose output is a fixed ADC level whatever the
// light and the exposure. Placed once per camera, from their own seed, at full-sensor positions
// (a region of interest is a window onto them); `defects_near_blob` of them within a radius of
// where the emitter's image falls, the others outside it.

#include <vector>

#include "sim/lab_scene_options.h"

namespace irdist::sim {

struct DefectPixel {
  enum class Kind { kHot, kStuck };
  int x_px = 0;  // full-sensor column and row
  int y_px = 0;
  Kind kind = Kind::kHot;
  double value = 0.0;  // hot: extra dark rate, electrons per second; stuck: output, ADC counts
};

// Draws the defects of `options` on a width x height sensor: every position distinct, the first
// `defects_near_blob` (a shuffled mix of hot and stuck) with pixel centres within
// near_blob_radius_px of (near_x_px, near_y_px), the others beyond it. Throws irdist::Error when
// the sensor has no room for them.
std::vector<DefectPixel> PlaceDefectPixels(const DefectPixelOptions& options, int width_px,
                                           int height_px, double near_x_px, double near_y_px);

}  // namespace irdist::sim
