#include "estimator/defect_map.h"

#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "tests/estimator/scene_render.h"

namespace irdist {
namespace {

TEST(DefectMapOptions, DefaultsAreValid) {
  std::string why;
  EXPECT_TRUE(DefectMapOptions().IsValid(&why)) << why;
  DefectMapOptions bad;
  bad.min_share = 0.0;
  EXPECT_FALSE(bad.IsValid(&why));
}

// A hot pixel, a stuck one at mid-scale and one stuck at 0 on every frame of a calibration (the
// disc moving over them, its brightness changing): in the map, in sensor coordinates; no other.
TEST(DefectMapFinder, FindsThePixelsThatAreDefectsOnMostFrames) {
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const int side = 96;
  DefectMapFinder finder(12, SceneOptions());
  const std::vector<cv::Point> defects = {{40, 41}, {70, 20}, {48, 48}};
  for (int i = 0; i < 20; ++i) {
    testing::SceneDisc d;
    d.cx = 30.0 + 36.0 * u(rng), d.cy = 30.0 + 36.0 * u(rng);
    d.a = d.b = 6.0 + 3.0 * u(rng);
    d.amplitude_e = 1000.0 + 8000.0 * u(rng);
    cv::Mat frame = testing::SensorFrame(testing::RenderScene(side, 60.0, {d}, 0.7),
                                         testing::NormalField(side, &rng));
    frame.at<uint16_t>(defects[0]) = 3900;
    frame.at<uint16_t>(defects[1]) = 2048;
    frame.at<uint16_t>(defects[2]) = 0;
    finder.Add(frame);
  }
  const DefectMap map = finder.Map(cv::Rect(100, 200, side, side));
  std::vector<cv::Point> expected;
  for (const cv::Point& p : defects) expected.push_back(p + cv::Point(100, 200));
  std::vector<cv::Point> found = map.sensor_px;
  auto by_yx = [](const cv::Point& a, const cv::Point& b) {
    return a.y != b.y ? a.y < b.y : a.x < b.x;
  };
  std::sort(found.begin(), found.end(), by_yx);
  std::sort(expected.begin(), expected.end(), by_yx);
  EXPECT_EQ(found, expected);
  EXPECT_EQ(map.roi, cv::Rect(100, 200, side, side));
  // Too few frames: no map.
  DefectMapFinder few(12, SceneOptions());
  few.Add(cv::Mat(side, side, CV_16UC1, cv::Scalar(40)));
  EXPECT_TRUE(few.Map(cv::Rect()).empty());
}

}  // namespace
}  // namespace irdist
