// The lab scene's and the defect pixels' options checked (sim/lab_scene_options.h): defaults
// (all off) pass; each bad field is refused with the rig file's key naming it.
#include "sim/lab_scene_options.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace irdist::sim {
namespace {

// `why` starts with `key`.
void ExpectKey(const std::string& why, const std::string& key) {
  EXPECT_EQ(why.rfind(key, 0), 0u) << why;
}

TEST(LabSceneOptions, AllOffIsValid) {
  std::string why;
  EXPECT_TRUE(LabSceneOptions().IsValid(&why)) << why;
  EXPECT_TRUE(DefectPixelOptions().IsValid(4095, &why)) << why;
  EXPECT_FALSE(LabSceneOptions().ambient.On());
  EXPECT_FALSE(LabSceneOptions().reflection.On());
  EXPECT_FALSE(LabSceneOptions().second_source.On());
  EXPECT_FALSE(LabSceneOptions().occluder.On());
}

TEST(LabSceneOptions, EachPartRefusesItsBadFieldByKey) {
  std::string why;
  LabSceneOptions scene;
  scene.ambient.center_e_per_s = -1.0;
  EXPECT_FALSE(scene.IsValid(&why));
  ExpectKey(why, "scene.ambient.center_e_per_s");
  scene = LabSceneOptions();
  scene.ambient.gradient_x_percent = 150.0;
  scene.ambient.gradient_y_percent = -60.0;  // |gx| + |gy| = 210: a corner would go negative
  EXPECT_FALSE(scene.IsValid(&why));
  ExpectKey(why, "scene.ambient.gradient_x_percent");
  scene = LabSceneOptions();
  scene.reflection.reflectance = 1.5;
  EXPECT_FALSE(scene.IsValid(&why));
  ExpectKey(why, "scene.reflection.reflectance");
  scene = LabSceneOptions();
  scene.second_source.position_mm = {0.0, 0.0, 50.0};  // behind the 100 mm minimum
  EXPECT_FALSE(scene.IsValid(&why));
  ExpectKey(why, "scene.second_source.position_mm");
  scene = LabSceneOptions();
  scene.second_source.diameter_mm = 200.0;  // more than 0.05 x 2000 mm
  EXPECT_FALSE(scene.IsValid(&why));
  ExpectKey(why, "scene.second_source.diameter_mm");
  scene = LabSceneOptions();
  scene.occluder.covered_fraction = 0.99;
  EXPECT_FALSE(scene.IsValid(&why));
  ExpectKey(why, "scene.occluder.covered_fraction");
  scene = LabSceneOptions();
  scene.occluder.edge_angle_deg = NAN;
  EXPECT_FALSE(scene.IsValid(&why));
  ExpectKey(why, "scene.occluder.edge_angle_deg");
}

TEST(DefectPixelOptions, RefusesEachBadFieldByKey) {
  std::string why;
  DefectPixelOptions d;
  d.hot_pixels = -1;
  EXPECT_FALSE(d.IsValid(4095, &why));
  ExpectKey(why, "sensor.hot_pixels");
  d = DefectPixelOptions();
  d.hot_rate_e_per_s = {300000.0, 180000.0};  // lo above hi
  EXPECT_FALSE(d.IsValid(4095, &why));
  ExpectKey(why, "sensor.hot_rate_e_per_s");
  d = DefectPixelOptions();
  d.stuck_pixels = 3;
  d.stuck_level_dn = {2000.0, 5000.0};  // above a 12-bit ADC's 4095
  EXPECT_FALSE(d.IsValid(4095, &why));
  ExpectKey(why, "sensor.stuck_level_dn");
  EXPECT_NE(why.find("4095"), std::string::npos) << why;
  EXPECT_TRUE(d.IsValid(65535, &why)) << why;  // fine on 16 bits
  d = DefectPixelOptions();
  d.hot_pixels = 2;
  d.defects_near_blob = 3;  // more than there are
  EXPECT_FALSE(d.IsValid(4095, &why));
  ExpectKey(why, "sensor.defects_near_blob");
  d = DefectPixelOptions();
  d.hot_pixels = 1000;
  d.near_blob_radius_px = 2.0;
  d.defects_near_blob = 10;  // pi 2^2 / 2 = 6.3 pixels at most
  EXPECT_FALSE(d.IsValid(4095, &why));
  ExpectKey(why, "sensor.defects_near_blob");
  EXPECT_EQ(d.Count(), 1000);
}

}  // namespace
}  // namespace irdist::sim
