#include "sim/lab_scene_options.h"

#include <cmath>
#include <string>

#include "base/pi.h"

namespace irdist::sim {
namespace {

bool Fail(std::string* why, const std::string& message) {
  if (why != nullptr) *why = message;
  return false;
}

bool In(double value, double lo, double hi) {
  return std::isfinite(value) && value >= lo && value <= hi;
}

// A [lo, hi] range inside [min, max].
bool RangeIn(const std::array<double, 2>& range, double min, double max) {
  return In(range[0], min, max) && In(range[1], min, max) && range[0] <= range[1];
}


}  // namespace

bool DefectPixelOptions::IsValid(int adc_max, std::string* why) const {
  if (hot_pixels < 0 || hot_pixels > 100000) {
    return Fail(why, "sensor.hot_pixels must be 0..100000");
  }
  if (stuck_pixels < 0 || stuck_pixels > 100000) {
    return Fail(why, "sensor.stuck_pixels must be 0..100000");
  }
  if (!RangeIn(hot_rate_e_per_s, 0.0, 1e9)) {
    return Fail(why, "sensor.hot_rate_e_per_s must be [lo, hi] with 0 <= lo <= hi <= 1e9");
  }
  const double level_max = stuck_pixels > 0 ? adc_max : 65535.0;
  if (!RangeIn(stuck_level_dn, 0.0, level_max)) {
    return Fail(why, "sensor.stuck_level_dn must be [lo, hi] with 0 <= lo <= hi <= 2^adc_bits - 1 (" +
                         std::to_string(adc_max) + ")");
  }
  if (!In(near_blob_radius_px, 1.0, 200.0)) {
    return Fail(why, "sensor.near_blob_radius_px must lie in [1, 200]");
  }
  if (defects_near_blob < 0 || defects_near_blob > Count()) {
    return Fail(why, "sensor.defects_near_blob must be 0..hot_pixels + stuck_pixels");
  }
  if (defects_near_blob > 0.5 * kPi * near_blob_radius_px * near_blob_radius_px) {
    return Fail(why, "sensor.defects_near_blob must be at most half the pixels within "
                     "near_blob_radius_px (pi r^2 / 2); raise the radius or lower the count");
  }
  return true;
}

bool AmbientOptions::IsValid(std::string* why) const {
  if (!In(center_e_per_s, 0.0, 1e8)) {
    return Fail(why, "scene.ambient.center_e_per_s must lie in [0, 1e8]");
  }
  if (!std::isfinite(gradient_x_percent) || !std::isfinite(gradient_y_percent) ||
      std::fabs(gradient_x_percent) + std::fabs(gradient_y_percent) > 200.0) {
    return Fail(why, "scene.ambient.gradient_x_percent (and gradient_y_percent) must be finite with "
                     "|gx| + |gy| <= 200 (the light stays >= 0 in every corner)");
  }
  return true;
}

bool ReflectionOptions::IsValid(std::string* why) const {
  if (!In(plane_below_mm, 0.0, 1000.0)) {
    return Fail(why, "scene.reflection.plane_below_mm must lie in [0, 1000]");
  }
  if (!In(reflectance, 0.0, 1.0)) return Fail(why, "scene.reflection.reflectance must lie in [0, 1]");
  return true;
}

bool SecondSourceOptions::IsValid(std::string* why) const {
  if (!In(position_mm[0], -10000.0, 10000.0) || !In(position_mm[1], -10000.0, 10000.0) ||
      !In(position_mm[2], 100.0, 100000.0)) {
    return Fail(why, "scene.second_source.position_mm must be [x, y, z] with |x|, |y| <= 10000 "
                     "and z in [100, 100000] (in front of the camera)");
  }
  if (!In(diameter_mm, 1e-3, 0.05 * position_mm[2])) {
    return Fail(why, "scene.second_source.diameter_mm must lie in [0.001, 0.05 z] (a source "
                     "seen under at most 0.05 rad, ~150 px with the default optics)");
  }
  if (!In(intensity_mw_sr, 0.0, 1e6)) {
    return Fail(why, "scene.second_source.intensity_mw_sr must lie in [0, 1e6]");
  }
  return true;
}

bool OccluderOptions::IsValid(std::string* why) const {
  if (!In(covered_fraction, 0.0, 0.95)) {
    return Fail(why, "scene.occluder.covered_fraction must lie in [0, 0.95]");
  }
  if (!In(edge_angle_deg, -360.0, 360.0)) {
    return Fail(why, "scene.occluder.edge_angle_deg must lie in [-360, 360]");
  }
  return true;
}

bool LabSceneOptions::IsValid(std::string* why) const {
  return ambient.IsValid(why) && reflection.IsValid(why) && second_source.IsValid(why) &&
         occluder.IsValid(why);
}

}  // namespace irdist::sim
