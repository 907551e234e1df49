// The scene pass's look at the IRED's shape (estimator/scene_occlusion.cc: AssessShape), through
// its estimator-internal header, on discs drawn by the independent renderer
// (tests/estimator/scene_render.h).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "estimator/scene.h"
#include "estimator/scene_internal.h"
#include "tests/estimator/scene_render.h"

namespace irdist::scene {
namespace {

using testing::RenderScene;
using testing::SceneDisc;
using testing::SensorFrame;

constexpr int kSide = 96;

// What the scene pass hands AssessShape: the frame's noise model and its segments.
struct Shape {
  SceneReport report;
  Segments segments;
};

Shape Assess(const cv::Mat& image, const SceneOptions& options = SceneOptions()) {
  Shape out;
  NoiseModel noise = MeasureBackgroundNoise(image, 12);
  noise.shot_gain = 0.39;
  out.segments = Segment(image, noise, options, SceneContext());
  EXPECT_GE(out.segments.ired, 0);
  if (out.segments.ired >= 0) AssessShape(image, out.segments, noise, options, &out.report);
  return out;
}

cv::Mat Frame(const std::vector<SceneDisc>& discs, double blur_px = 0.7) {
  return SensorFrame(RenderScene(kSide, 100.0, discs, blur_px), cv::Mat1d());
}

SceneDisc Disc(double a, double b, double angle_deg) {
  SceneDisc d;
  d.cx = 48.3;
  d.cy = 47.6;
  d.a = a;
  d.b = b;
  d.angle_deg = angle_deg;
  d.amplitude_e = 6000.0;
  return d;
}

// A whole disc, round or tilted to an axis ratio of 0.87 (30 deg), keeps its half-maximum edge on
// an ellipse: no ray departs, nothing occluded, no second source.
TEST(SceneShape, WholeDiscsAreNeitherOccludedNorMerged) {
  for (const SceneDisc& d : {Disc(9.0, 9.0, 0.0), Disc(10.0, 8.7, 35.0), Disc(6.0, 5.2, 100.0)}) {
    const Shape s = Assess(Frame({d}));
    EXPECT_FALSE(s.report.occluded) << "a=" << d.a << " b=" << d.b;
    EXPECT_EQ(s.report.occluded_edge_fraction, 0.0) << "a=" << d.a;
    EXPECT_FALSE(s.report.second_source) << "a=" << d.a;
  }
}

// A straight occluder taking 10 % of the disc bends its edge over a chord of some 70 deg of the
// rays: far more than occluded_min_fraction (3 %) of them depart.
TEST(SceneShape, ACutDiscIsOccluded) {
  SceneDisc d = Disc(9.0, 9.0, 0.0);
  d.cut = 0.10;
  d.cut_angle_deg = 60.0;
  const Shape s = Assess(Frame({d}));
  EXPECT_TRUE(s.report.occluded);
  EXPECT_GT(s.report.occluded_edge_fraction, 0.1);
  EXPECT_LT(s.report.occluded_edge_fraction, 0.5);
}

// detect_occlusion off: the fraction is not reported (the merged-source check still runs).
TEST(SceneShape, OcclusionOffLeavesTheReportAlone) {
  SceneDisc d = Disc(9.0, 9.0, 0.0);
  d.cut = 0.10;
  SceneOptions options;
  options.detect_occlusion = false;
  const Shape s = Assess(Frame({d}), options);
  EXPECT_FALSE(s.report.occluded);
  EXPECT_EQ(s.report.occluded_edge_fraction, 0.0);
}

// A dimmer LED (a third of the plateau) touching the disc merges into its component at the
// segmentation's low threshold: the pixels beyond the disc's ellipse name it a second source at
// a gap of 0.
TEST(SceneShape, ADimmerSourceMergedWithTheDiscIsASecondSource) {
  SceneDisc second = Disc(4.0, 4.0, 0.0);
  second.cx += 12.0;
  second.amplitude_e = 2000.0;
  const Shape s = Assess(Frame({Disc(9.0, 9.0, 0.0), second}));
  ASSERT_EQ(s.segments.blobs.size(), 1u);  // one component
  EXPECT_TRUE(s.report.second_source);
  EXPECT_EQ(s.report.second_source_gap_px, 0.0);
}

// A blob under occlusion_min_radius_px (area < pi 3^2) has too few edge pixels: not assessed.
TEST(SceneShape, SmallBlobsAreNotAssessed) {
  SceneDisc d = Disc(2.0, 2.0, 0.0);
  d.cut = 0.3;
  const Shape s = Assess(Frame({d}, 0.5));
  EXPECT_LT(s.segments.blobs[s.segments.ired].area, 3.14159 * 9.0);
  EXPECT_FALSE(s.report.occluded);
  EXPECT_EQ(s.report.occluded_edge_fraction, 0.0);
  EXPECT_FALSE(s.report.second_source);
  // The same cut at radius 9 is seen, unless the minimum radius is raised above that of a disc
  // of its component's area (70 % of the disc, grown by the blur's wings above the threshold).
  SceneDisc big = Disc(9.0, 9.0, 0.0);
  big.cut = 0.3;
  const Shape seen = Assess(Frame({big}));
  EXPECT_TRUE(seen.report.occluded);
  const double radius = std::sqrt(seen.segments.blobs[seen.segments.ired].area / 3.14159);
  ASSERT_LT(radius, 9.5);
  SceneOptions options;
  options.occlusion_min_radius_px = 9.5;
  const Shape unassessed = Assess(Frame({big}), options);
  EXPECT_FALSE(unassessed.report.occluded);
  EXPECT_EQ(unassessed.report.occluded_edge_fraction, 0.0);
}

}  // namespace
}  // namespace irdist::scene
