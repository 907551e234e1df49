#pragma once
// The lab around the IRED (virtual.scene:, sim/lab_scene_options.h; docs/virtual-rig.md "A lab's
// scene"): the light that reaches the sensor besides the IRED's own. Each is physics in the scene,
// rendered through the same optics as the IRED (sim/scene.h RenderDisc):
// - the IRED's reflection off the table: a virtual emitter mirrored in the horizontal plane
//   `plane_below_mm` below the emitter's centre (position and emission axis mirrored), its light
//   scaled by the reflectance; it follows the current, the thermal state and the pan/tilt;
// - a second, constant source: a uniformly bright (Lambertian) disc facing the camera at a fixed
//   position, independent of the IRED's current;
// - ambient infrared light: a smooth background proportional to the exposure.
// The occluder over the IRED's disc is part of the IRED's own image (Scene::EmitterDisc).

#include <optional>

#include <opencv2/core.hpp>

#include "sim/scene.h"

namespace irdist::sim {

class LabScene {
 public:
  // Reads scene.physics().scene; `scene` must outlive this object.
  explicit LabScene(const Scene& scene);

  // The IRED's mirror image for the pose at on-axis intensity `intensity_mw_sr` (the IRED's), or
  // none when the reflection is off or the camera is not above the table.
  std::optional<DiscSource> ReflectionDisc(const PoseState& pose, double intensity_mw_sr) const;
  // The second source, or none when off.
  std::optional<DiscSource> SecondSourceDisc() const;

  // Ambient photo-electrons per pixel per second at the centre of full-sensor pixel (x, y).
  double AmbientRateEPerS(int x_px, int y_px) const;
  // The ambient mean photo-electrons over `rect` (full-sensor pixels) for `exposure_s`.
  SignalWindow Ambient(const cv::Rect& rect, double exposure_s) const;

  bool ReflectionOn() const { return options_.reflection.On(); }
  bool SecondSourceOn() const { return options_.second_source.On(); }
  bool AmbientOn() const { return options_.ambient.On(); }

 private:
  const Scene& scene_;
  LabSceneOptions options_;
};

}  // namespace irdist::sim
