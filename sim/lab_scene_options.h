#pragma once
// The lab's faults of the virtual rig, all off by default (docs/virtual-rig.md "A lab's scene"):
// defect pixels on the sensor (`virtual.sensor:`), and in the scene (`virtual.scene:`) ambient
// infrared light, the IRED's reflection off the table, a second constant infrared source and an
// occluder over the IRED's disc. Read and checked with the rest of the rig file's `virtual:`
// section (sim/rig_physics.h LoadRigPhysics).

#include <array>
#include <cstdint>
#include <string>

namespace irdist::sim {

// Defect pixels (sensor), drawn once per camera from `defect_seed` at full-sensor positions.
struct DefectPixelOptions {
  int hot_pixels = 0;  // pixels with a fixed extra dark signal that grows with the exposure
  // Each hot pixel's dark rate is drawn uniformly from this range (electrons per second): the
  // default reads 60-100% of the default full well (10500 e-) at a 35 ms exposure.
  std::array<double, 2> hot_rate_e_per_s = {180000.0, 300000.0};
  int stuck_pixels = 0;  // pixels whose output is a fixed level, whatever the light and exposure
  // Each stuck pixel's level is drawn uniformly from this range (ADC counts, <= 2^adc_bits - 1).
  std::array<double, 2> stuck_level_dn = {2000.0, 4095.0};
  std::uint64_t defect_seed = 1;  // positions, rates and levels
  // How many of the defects (hot and stuck, shuffled) lie within near_blob_radius_px of the
  // emitter's image centre (Scene::Project at the default pose); the others lie outside it.
  int defects_near_blob = 0;
  double near_blob_radius_px = 10.0;
  int Count() const { return hot_pixels + stuck_pixels; }
  bool IsValid(int adc_max, std::string* why) const;
};

// Ambient infrared light (scene): a smooth background of photo-electrons, proportional to the
// exposure, independent of the IRED, with shot noise like any light. 0 = off.
struct AmbientOptions {
  double center_e_per_s = 0.0;  // photo-electrons per pixel per second at the sensor's centre
  // Linear change across the sensor's full width (height), in % of the centre's value: the rate at
  // pixel (x, y) is centre x (1 + gx/100 (x - W/2)/W + gy/100 (y - H/2)/H), pixel centres.
  double gradient_x_percent = 0.0;
  double gradient_y_percent = 0.0;
  bool On() const { return center_e_per_s > 0.0; }
  bool IsValid(std::string* why) const;
};

// The IRED's mirror image in the table, a horizontal plane `plane_below_mm` below the emitter's
// centre (image +y is down): a virtual emitter at the mirrored position with the mirrored axis, its
// light scaled by `reflectance`. 0 = off.
struct ReflectionOptions {
  double plane_below_mm = 0.0;
  double reflectance = 0.0;
  bool On() const { return plane_below_mm > 0.0 && reflectance > 0.0; }
  bool IsValid(std::string* why) const;
};

// A second, constant infrared source: a uniformly bright disc facing the camera at a fixed place
// in the camera's frame (mm: x right, y down, z along the optical axis). 0 intensity = off.
struct SecondSourceOptions {
  std::array<double, 3> position_mm = {0.0, 0.0, 2000.0};
  double diameter_mm = 5.0;  // at most 0.05 x z (its image stays a small part of the sensor)
  double intensity_mw_sr = 0.0;  // radiant intensity towards the camera (radiance I / area)
  bool On() const { return intensity_mw_sr > 0.0; }
  bool IsValid(std::string* why) const;
};

// An opaque straight edge (a cable) in the emitter's plane, moving with it, covering
// `covered_fraction` of the disc's area from the direction `edge_angle_deg` in the disc's plane:
// measured from the disc's +x axis towards its +y axis, which are the image's x (right) and y
// (down) when the disc faces the camera (pan = tilt = 0): 0 covers the right side, 90 the bottom,
// 180 the left, 270 the top. 0 = off.
struct OccluderOptions {
  double covered_fraction = 0.0;
  double edge_angle_deg = 90.0;
  bool On() const { return covered_fraction > 0.0; }
  bool IsValid(std::string* why) const;
};

struct LabSceneOptions {
  AmbientOptions ambient;
  ReflectionOptions reflection;
  SecondSourceOptions second_source;
  OccluderOptions occluder;
  bool IsValid(std::string* why) const;
};

}  // namespace irdist::sim
