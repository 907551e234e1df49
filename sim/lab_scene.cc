#include "sim/lab_scene.h"

#include <cmath>

namespace irdist::sim {

LabScene::LabScene(const Scene& scene) : scene_(scene), options_(scene.physics().scene) {}

std::optional<DiscSource> LabScene::ReflectionDisc(const PoseState& pose,
                                                   double intensity_mw_sr) const {
  const ReflectionOptions& r = options_.reflection;
  if (!r.On()) return std::nullopt;
  DiscSource disc = scene_.EmitterDisc(pose, intensity_mw_sr);
  // The table is the plane y = y_c + h (image y points down); the camera (y = 0) must be above it.
  const double plane_y_mm = disc.center_mm[1] + r.plane_below_mm;
  if (plane_y_mm <= 0.0) return std::nullopt;
  disc.center_mm[1] = 2.0 * plane_y_mm - disc.center_mm[1];
  disc.axis[1] = -disc.axis[1];
  disc.cut_direction[1] = -disc.cut_direction[1];  // the occluder's mirror image too
  disc.intensity_mw_sr = r.reflectance * intensity_mw_sr;
  return disc;
}

std::optional<DiscSource> LabScene::SecondSourceDisc() const {
  const SecondSourceOptions& o = options_.second_source;
  if (!o.On()) return std::nullopt;
  DiscSource disc;
  disc.center_mm = o.position_mm;
  const double d = std::sqrt(o.position_mm[0] * o.position_mm[0] +
                             o.position_mm[1] * o.position_mm[1] +
                             o.position_mm[2] * o.position_mm[2]);
  disc.axis = {-o.position_mm[0] / d, -o.position_mm[1] / d, -o.position_mm[2] / d};  // facing us
  disc.diameter_mm = o.diameter_mm;
  disc.intensity_mw_sr = o.intensity_mw_sr;
  disc.lambertian = true;
  return disc;
}

double LabScene::AmbientRateEPerS(int x_px, int y_px) const {
  const AmbientOptions& a = options_.ambient;
  const SensorOptions& s = scene_.physics().sensor;
  const double u = (x_px + 0.5 - 0.5 * s.width_px) / s.width_px;
  const double v = (y_px + 0.5 - 0.5 * s.height_px) / s.height_px;
  return a.center_e_per_s *
         std::max(0.0, 1.0 + a.gradient_x_percent / 100.0 * u + a.gradient_y_percent / 100.0 * v);
}

SignalWindow LabScene::Ambient(const cv::Rect& rect, double exposure_s) const {
  SignalWindow out;
  out.rect = rect;
  out.electrons = cv::Mat1f::zeros(rect.height, rect.width);
  if (!AmbientOn() || exposure_s <= 0.0) return out;
  for (int r = 0; r < rect.height; ++r) {
    float* dst = out.electrons[r];
    for (int c = 0; c < rect.width; ++c) {
      dst[c] = static_cast<float>(AmbientRateEPerS(rect.x + c, rect.y + r) * exposure_s);
    }
  }
  return out;
}

}  // namespace irdist::sim
