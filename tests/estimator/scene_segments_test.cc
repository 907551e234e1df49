// The scene pass's segmentation (estimator/scene_segments.cc), through its estimator-internal
// header, on hand-drawn noise-free frames whose components are known by construction.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "estimator/scene.h"
#include "estimator/scene_internal.h"

namespace irdist::scene {
namespace {

constexpr double kBackground = 100.0;

cv::Mat Blank(int side = 64) { return cv::Mat(side, side, CV_16UC1, cv::Scalar(kBackground)); }

void Square(cv::Mat* image, cv::Rect r, double level) { (*image)(r).setTo(cv::Scalar(level)); }

NoiseModel Noise() {
  NoiseModel n;
  n.background = kBackground;
  n.read_sd = 2.0;
  return n;
}

// Threshold: background + max(6 x read sd, 2 % of the peak above background); the components'
// areas, fluxes (sum of g - background) and intensity centroids; the IRED the one of most flux.
TEST(SceneSegment, ComponentsTheirFluxAndTheIred) {
  cv::Mat image = Blank();
  Square(&image, cv::Rect(10, 10, 5, 5), 1100.0);  // 25 px x 1000 DN
  Square(&image, cv::Rect(40, 30, 8, 6), 400.0);   // 48 px x 300 DN
  const Segments s = Segment(image, Noise(), SceneOptions(), SceneContext());
  EXPECT_DOUBLE_EQ(s.threshold, kBackground + std::max(12.0, 0.02 * 1000.0));
  ASSERT_EQ(s.blobs.size(), 2u);
  const Blob& a = s.blobs[0];
  EXPECT_EQ(a.area, 25);
  EXPECT_EQ(a.rect, cv::Rect(10, 10, 5, 5));
  EXPECT_DOUBLE_EQ(a.flux, 25000.0);
  EXPECT_NEAR(a.centroid.x, 12.0, 1e-12);
  EXPECT_NEAR(a.centroid.y, 12.0, 1e-12);
  const Blob& b = s.blobs[1];
  EXPECT_EQ(b.area, 48);
  EXPECT_DOUBLE_EQ(b.flux, 48 * 300.0);
  EXPECT_NEAR(b.centroid.x, 43.5, 1e-12);
  EXPECT_NEAR(b.centroid.y, 32.5, 1e-12);
  EXPECT_EQ(s.ired, 0);
  EXPECT_EQ(s.labels.at<std::int32_t>(12, 12), a.label);
  EXPECT_EQ(s.labels.at<std::int32_t>(32, 43), b.label);
  EXPECT_EQ(s.labels.at<std::int32_t>(0, 0), 0);
  // An expected centre picks the nearest component instead.
  SceneContext near_b;
  near_b.has_expected_center = true;
  near_b.expected_center_px = cv::Point2d(50.0, 40.0);
  EXPECT_EQ(Segment(image, Noise(), SceneOptions(), near_b).ired, 1);
}

// 8-connected: pixels touching at a corner are one component, and a U whose arms meet only at
// its bottom row (two labels joined late) is one component too. A lone bright pixel below
// min_blob_area_px is never the IRED however bright.
TEST(SceneSegment, EightConnectedComponentsAndTheSmallestIred) {
  cv::Mat image = Blank();
  image.at<std::uint16_t>(5, 5) = 600;
  image.at<std::uint16_t>(6, 6) = 600;
  Square(&image, cv::Rect(20, 20, 1, 6), 600.0);  // the U's left arm
  Square(&image, cv::Rect(26, 20, 1, 6), 600.0);  // its right arm
  Square(&image, cv::Rect(20, 25, 7, 1), 600.0);  // its bottom
  image.at<std::uint16_t>(50, 50) = 20000;  // more flux than the U, but one pixel
  const Segments s = Segment(image, Noise(), SceneOptions(), SceneContext());
  ASSERT_EQ(s.blobs.size(), 3u);
  EXPECT_EQ(s.blobs[0].area, 2);
  EXPECT_EQ(s.blobs[1].area, 6 + 6 + 5);
  EXPECT_EQ(s.blobs[1].rect, cv::Rect(20, 20, 7, 6));
  EXPECT_EQ(s.blobs[2].area, 1);
  EXPECT_EQ(s.ired, 1);  // the U: most flux among those of 2 px or more
  // Nothing above the threshold: no blob, no IRED.
  const Segments none = Segment(Blank(), Noise(), SceneOptions(), SceneContext());
  EXPECT_TRUE(none.blobs.empty());
  EXPECT_EQ(none.ired, -1);
}

// A replaced defect leaves its component; a component of defects alone is gone; the IRED is
// picked again among what is left.
TEST(SceneSegment, ForgetDefectsDropsReplacedPixels) {
  cv::Mat image = Blank();
  Square(&image, cv::Rect(10, 10, 4, 4), 300.0);  // 16 px x 200
  Square(&image, cv::Rect(40, 40, 2, 1), 4000.0);  // two hot pixels: the most flux
  image.at<std::uint16_t>(13, 14) = 3000;          // a hot pixel on the blob's edge
  Segments s = Segment(image, Noise(), SceneOptions(), SceneContext());
  ASSERT_EQ(s.blobs.size(), 2u);
  ASSERT_EQ(s.blobs[s.ired].area, 2);
  cv::Mat cleaned = image.clone();
  const std::vector<cv::Point> defects = {{40, 40}, {41, 40}, {14, 13}};
  for (const cv::Point& p : defects) cleaned.at<std::uint16_t>(p) = 100;
  ForgetDefects(cleaned, defects, SceneOptions(), SceneContext(), &s);
  ASSERT_EQ(s.blobs.size(), 1u);
  EXPECT_EQ(s.ired, 0);
  EXPECT_EQ(s.blobs[0].area, 16);
  EXPECT_DOUBLE_EQ(s.blobs[0].flux, 16 * 200.0);
  EXPECT_EQ(s.labels.at<std::int32_t>(40, 41), 0);
  EXPECT_EQ(s.labels.at<std::int32_t>(13, 14), 0);
}

// A blob grown by 2 px: every pixel within 2 px of it (the disc's structuring element), clipped
// to the frame.
TEST(SceneSegment, GrownMaskReachesTheGivenDistance) {
  cv::Mat image = Blank(32);
  image.at<std::uint16_t>(10, 10) = 600;
  image.at<std::uint16_t>(0, 31) = 600;
  image.at<std::uint16_t>(1, 31) = 600;
  const Segments s = Segment(image, Noise(), SceneOptions(), SceneContext());
  ASSERT_EQ(s.blobs.size(), 2u);
  const LocalMask m = GrownMask(s, s.blobs[1], 2.0, image.size());
  EXPECT_EQ(m.box, cv::Rect(8, 8, 5, 5));
  EXPECT_TRUE(m.Has({10, 10}));
  EXPECT_TRUE(m.Has({12, 10}));
  EXPECT_TRUE(m.Has({10, 8}));
  EXPECT_TRUE(m.Has({11, 11}));
  EXPECT_FALSE(m.Has({12, 12}));  // 2.8 px away
  EXPECT_FALSE(m.Has({13, 10}));
  const LocalMask corner = GrownMask(s, s.blobs[0], 2.0, image.size());
  EXPECT_EQ(corner.box, cv::Rect(29, 0, 3, 4));
  const LocalMask ungrown = GrownMask(s, s.blobs[1], 0.0, image.size());
  EXPECT_EQ(ungrown.box, cv::Rect(10, 10, 1, 1));
}

// Another blob far from the IRED is filled with its surroundings' mean level and counted when
// near the features' window; one within two halo reaches of the IRED is its second source.
TEST(SceneSegment, OtherBlobsAreMaskedOrNamedASecondSource) {
  cv::Mat image = Blank(96);
  Square(&image, cv::Rect(40, 40, 6, 6), 2100.0);  // the IRED
  Square(&image, cv::Rect(60, 42, 3, 3), 900.0);   // 14 px to its right
  Square(&image, cv::Rect(5, 85, 2, 2), 900.0);    // far outside a 64 px window
  image(cv::Rect(50, 30, 30, 30)).setTo(cv::Scalar(120), image(cv::Rect(50, 30, 30, 30)) == 100);
  Segments s = Segment(image, Noise(), SceneOptions(), SceneContext());
  ASSERT_EQ(s.blobs.size(), 3u);
  ASSERT_EQ(s.blobs[s.ired].rect, cv::Rect(40, 40, 6, 6));
  SceneReport report;
  cv::Mat cleaned = image.clone();
  MaskOtherBlobs(s, SceneOptions(), SceneContext(), &cleaned, &report);
  EXPECT_EQ(report.other_blobs, 1);
  ASSERT_EQ(report.other_blob_rects.size(), 1u);
  EXPECT_EQ(report.other_blob_rects[0], cv::Rect(60, 42, 3, 3));
  EXPECT_FALSE(report.second_source);
  EXPECT_DOUBLE_EQ(report.second_source_gap_px, 60.0 - 45.0 - 1.0);
  EXPECT_EQ(cleaned.at<std::uint16_t>(43, 61), 120);  // the local level around it
  EXPECT_EQ(cleaned.at<std::uint16_t>(86, 6), 100);
  EXPECT_EQ(cleaned.at<std::uint16_t>(42, 42), 2100);  // the IRED untouched
  // Moved to a gap of 3 px from the IRED (less than 2 x 2 px of halo): a second source.
  cv::Mat close = Blank(96);
  Square(&close, cv::Rect(40, 40, 6, 6), 2100.0);
  Square(&close, cv::Rect(49, 42, 3, 3), 900.0);
  s = Segment(close, Noise(), SceneOptions(), SceneContext());
  SceneReport near;
  MaskOtherBlobs(s, SceneOptions(), SceneContext(), &close, &near);
  EXPECT_TRUE(near.second_source);
  EXPECT_DOUBLE_EQ(near.second_source_gap_px, 3.0);
}

}  // namespace
}  // namespace irdist::scene
