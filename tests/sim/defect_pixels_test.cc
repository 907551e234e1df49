#include "sim/defect_pixels.h"

#include <cmath>
#include <set>
#include <utility>

#include <gtest/gtest.h>

#include "sim/renderer.h"

namespace irdist::sim {
namespace {

DefectPixelOptions ThirtyDefects() {
  DefectPixelOptions d;
  d.hot_pixels = 20;
  d.stuck_pixels = 10;
  d.stuck_level_dn = {1000.0, 3000.0};
  d.defect_seed = 11;
  d.defects_near_blob = 3;
  d.near_blob_radius_px = 10.0;
  return d;
}

// Distinct places, the near ones within the radius of the given point and the others beyond it,
// the same for the same seed.
TEST(DefectPixels, PlacedFromTheSeedWithTheNearCount) {
  const DefectPixelOptions o = ThirtyDefects();
  const std::vector<DefectPixel> defects = PlaceDefectPixels(o, 1280, 1024, 600.0, 500.0);
  ASSERT_EQ(defects.size(), 30u);
  std::set<std::pair<int, int>> places;
  int near = 0, hot = 0;
  for (const DefectPixel& d : defects) {
    places.insert({d.x_px, d.y_px});
    if (std::hypot(d.x_px + 0.5 - 600.0, d.y_px + 0.5 - 500.0) <= 10.0) ++near;
    if (d.kind == DefectPixel::Kind::kHot) {
      ++hot;
      EXPECT_GE(d.value, o.hot_rate_e_per_s[0]);
      EXPECT_LE(d.value, o.hot_rate_e_per_s[1]);
    } else {
      EXPECT_GE(d.value, 1000.0);
      EXPECT_LE(d.value, 3000.0);
    }
  }
  EXPECT_EQ(places.size(), 30u);
  EXPECT_EQ(near, 3);
  EXPECT_EQ(hot, 20);
  const std::vector<DefectPixel> again = PlaceDefectPixels(o, 1280, 1024, 600.0, 500.0);
  for (size_t k = 0; k < defects.size(); ++k) EXPECT_EQ(again[k].x_px, defects[k].x_px);
  DefectPixelOptions other = o;
  other.defect_seed = 12;
  EXPECT_NE(PlaceDefectPixels(other, 1280, 1024, 600.0, 500.0)[5].x_px, defects[5].x_px);
}

// In the camera: a hot pixel reads its rate x exposure (60-100% of full scale at 35 ms with the
// default range), growing linearly; a stuck pixel reads its level whatever the exposure and the
// light; 3 of them within 10 px of the emitter's image centre (the sensor's centre on the axis).
TEST(DefectPixels, HotGrowWithExposureStuckStayAndThreeAreNearTheBlob) {
  RigPhysics p;
  p.sensor.defects = ThirtyDefects();
  const Renderer renderer(p);
  const SensorOptions& s = p.sensor;
  const std::vector<DefectPixel>& defects = renderer.sensor().defects();
  ASSERT_EQ(defects.size(), 30u);
  int near = 0;
  for (const DefectPixel& d : defects) near += std::hypot(d.x_px + 0.5 - 640, d.y_px + 0.5 - 512) <= 10;
  EXPECT_EQ(near, 3);
  auto frame = [&](double bias_ma, double exposure_s) {
    return renderer.Render(StaticConditions(2000, 0, 0, bias_ma, exposure_s), 1,
                           PixelFormat::kMono12);
  };
  const cv::Mat dark10 = frame(0, 0.010), dark35 = frame(0, 0.035), lit35 = frame(500, 0.035);
  for (const DefectPixel& d : defects) {
    const double at10 = dark10.at<std::uint16_t>(d.y_px, d.x_px);
    const double at35 = dark35.at<std::uint16_t>(d.y_px, d.x_px);
    if (d.kind == DefectPixel::Kind::kStuck) {
      EXPECT_EQ(at10, d.value);
      EXPECT_EQ(at35, d.value);
      EXPECT_EQ(lit35.at<std::uint16_t>(d.y_px, d.x_px), d.value);
      continue;
    }
    const double expected10 =
        s.black_level_dn + s.system_gain_dn_per_e * (d.value + s.dark_current_e_per_s) * 0.010;
    EXPECT_NEAR(at10, expected10, 5.0 * std::sqrt(expected10) + 3.0);  // shot noise, in DN
    EXPECT_GE(at35 / s.AdcMax(), 0.6 - 0.02);
    EXPECT_LE(at35 / s.AdcMax(), 1.0);
    if (at35 < s.AdcMax()) EXPECT_NEAR((at35 - 16) / (at10 - 16), 3.5, 0.15);
  }
  // A region of interest is a window onto the same defects, with the same values.
  cv::Mat roi(256, 256, CV_16UC1);
  renderer.Render(StaticConditions(2000, 0, 0, 0, 0.035), 1, PixelFormat::kMono12,
                  cv::Point(512, 384), roi);
  for (const DefectPixel& d : defects) {
    if (!cv::Rect(512, 384, 256, 256).contains(cv::Point(d.x_px, d.y_px))) continue;
    EXPECT_EQ(roi.at<std::uint16_t>(d.y_px - 384, d.x_px - 512),
              dark35.at<std::uint16_t>(d.y_px, d.x_px));
  }
}

// Off the axis the near defects gather around where the emitter's image falls.
TEST(DefectPixels, NearTheEmittersImageOffTheAxis) {
  RigPhysics p;
  p.emitter.offset_x_mm = 60.0;
  p.sensor.defects = ThirtyDefects();
  const Renderer renderer(p);
  const EmitterImage image = renderer.scene().Project(PoseState{});
  int near = 0;
  for (const DefectPixel& d : renderer.sensor().defects()) {
    near += std::hypot(d.x_px + 0.5 - image.center_x_px, d.y_px + 0.5 - image.center_y_px) <= 10;
  }
  EXPECT_EQ(near, 3);
  EXPECT_GT(image.center_x_px, 700.0);
}

}  // namespace
}  // namespace irdist::sim
