// Each frame's features, the same from the PNG as from memory (a live run's cache), and
// features.csv, on a small hand-made recording.
#include "app/processing/frame_features.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "acquisition/recording_reader.h"
#include "tests/app/small_recording.h"
#include "tests/estimator/scene_render.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;
using testing::ReadAll;
using testing::SmallRecordingTest;

TEST(OfflineBitDepth, FollowsThePixelFormat) {
  EXPECT_EQ(BitDepthOfPixelFormat("Mono8"), 8);
  EXPECT_EQ(BitDepthOfPixelFormat("Mono10"), 10);
  EXPECT_EQ(BitDepthOfPixelFormat("Mono12"), 12);
  EXPECT_EQ(BitDepthOfPixelFormat("Mono16"), 16);
}

// The scene pass runs inside FrameFeatures: a frame with hot pixels and a reflection gives the
// clean frame's features and says what it masked (Features::scene); SceneCleanedFrame is the frame
// FrameFeatures measured (what recording_fit hands to the blob fit and the blur split).
TEST(FrameFeatures, MeasuresTheSceneCleanedFrame) {
  std::mt19937_64 rng(8);
  testing::SceneDisc disc;
  disc.cx = 60.3, disc.cy = 58.8, disc.a = 8.0, disc.b = 7.3, disc.angle_deg = 40.0;
  testing::SceneDisc reflection = disc;
  reflection.cy += 8.0 + 8.0 + 15.0;
  reflection.amplitude_e *= 0.2;
  const cv::Mat1d z = testing::NormalField(128, &rng);
  const cv::Mat clean = testing::SensorFrame(testing::RenderScene(128, 50.0, {disc}, 0.7), z);
  cv::Mat bench = testing::SensorFrame(testing::RenderScene(128, 50.0, {disc, reflection}, 0.7), z);
  bench.at<uint16_t>(60, 60) = 3900;  // on the plateau
  bench.at<uint16_t>(40, 45) = 3000;  // in the background
  const FeatureOptions options;
  const Features a = FrameFeatures(bench, 12, options), b = FrameFeatures(clean, 12, options);
  ASSERT_TRUE(a.scene.assessed && a.Usable());
  EXPECT_EQ(a.scene.other_blobs, 1) << a.scene.BriefReport();
  EXPECT_EQ(a.scene.defect_pixels, 2) << a.scene.BriefReport();
  EXPECT_FALSE(a.scene.second_source || a.scene.occluded);
  EXPECT_NEAR(a.e_rel / b.e_rel, 1.0, 5e-4);
  EXPECT_NEAR(a.sigma / b.sigma, 1.0, 5e-4);
  EXPECT_NEAR(a.moment_major_var_px2 / b.moment_major_var_px2, 1.0, 2e-3);
  const Features c = ComputeFeatures(SceneCleanedFrame(bench, 12, options), 12, options);
  EXPECT_EQ(c.e_rel, a.e_rel);
  EXPECT_EQ(c.moment_major_var_px2, a.moment_major_var_px2);
  // Off: the frame as it is (the reflection inside the window).
  FeatureOptions off = options;
  off.scene.enabled = false;
  const Features raw = FrameFeatures(bench, 12, off);
  EXPECT_FALSE(raw.scene.assessed);
  EXPECT_GT(std::abs(raw.e_rel / b.e_rel - 1.0), 0.01);
}

// With a model the blob fit refines the frame and measures its own blur (estimator/refocus.h);
// given `later`, the features come without it and MeasurePendingOwnBlur adds exactly the same,
// once (measure --track answers before it).
TEST(FrameFeatures, MeasuresTheOwnBlurNowOrLater) {
  std::mt19937_64 rng(9);
  testing::SceneDisc disc;
  disc.cx = 60.3, disc.cy = 58.8, disc.a = 8.0, disc.b = 7.3, disc.angle_deg = 40.0;
  const cv::Mat frame = testing::SensorFrame(testing::RenderScene(128, 50.0, {disc}, 0.7),
                                             testing::NormalField(128, &rng));
  CalibrationModel model;  // the disc's size at 2000 mm, the rendering's blur
  model.geometric.beta_px2 = 0.7 * 0.7 + 1.0 / 12.0;
  model.geometric.alpha_px2 = 16.0 * 4.0;
  const FeatureOptions options;
  const Features now = FrameFeatures(frame, 12, options, &model);
  ASSERT_TRUE(std::isfinite(now.own_blur_var_px2)) << now.BriefReport();
  EXPECT_NEAR(now.own_blur_var_px2, model.geometric.beta_px2, 5.0 * now.own_blur_se_px2);
  PendingOwnBlur pending;
  Features later = FrameFeatures(frame, 12, options, &model, nullptr, &pending);
  EXPECT_TRUE(std::isnan(later.own_blur_var_px2));
  EXPECT_EQ(later.moment_major_var_px2, now.moment_major_var_px2);  // refined all the same
  ASSERT_EQ(pending.model, &model);
  EXPECT_TRUE(MeasurePendingOwnBlur(&pending, &later));
  EXPECT_EQ(later.own_blur_var_px2, now.own_blur_var_px2);
  EXPECT_EQ(later.own_blur_se_px2, now.own_blur_se_px2);
  EXPECT_EQ(later.own_major_var_px2, now.own_major_var_px2);
  EXPECT_EQ(pending.model, nullptr);
  EXPECT_FALSE(MeasurePendingOwnBlur(&pending, &later));  // nothing left
  // Without a model nothing is pending.
  FrameFeatures(frame, 12, options, nullptr, nullptr, &pending);
  EXPECT_EQ(pending.model, nullptr);
}

// The message FrameFeatures refuses `image` with (FeatureWindowError); "" when it measures it.
std::string WindowRefusal(const cv::Mat& image, const FeatureOptions& options) {
  try {
    FrameFeatures(image, 12, options);
  } catch (const FeatureWindowError& e) {
    return e.what();
  }
  return "";
}

// A model's features.window_side_px larger than the frame (a model without provenance, whose ROI
// was never checked against the window, on a 256 px ROI) is refused before the scene pass and the
// features, naming the key, the frame's size and the largest window that fits; it hit an internal
// check in ComputeFeatures. A frame exactly the window's size is measured.
TEST(FrameFeatures, RefusesAFrameSmallerThanTheWindow) {
  FeatureOptions options;
  options.window_side_px = 512;
  const cv::Mat roi(256, 256, CV_16UC1, cv::Scalar(100));
  const std::string what = WindowRefusal(roi, options);
  EXPECT_NE(what.find("features.window_side_px 512"), std::string::npos) << what;
  EXPECT_NE(what.find("256 x 256 px"), std::string::npos) << what;
  EXPECT_NE(what.find("at most 256"), std::string::npos) << what;
  // The scene pass alone (recording_fit's blob fit and blur split) refuses it too.
  EXPECT_THROW(SceneCleanedFrame(roi, 12, options), FeatureWindowError);
  // Either side too short: a wide, low ROI names its height as the largest window.
  options.window_side_px = 128;
  const std::string wide = WindowRefusal(cv::Mat(100, 300, CV_16UC1, cv::Scalar(100)), options);
  EXPECT_NE(wide.find("300 x 100 px (width x height)"), std::string::npos) << wide;
  EXPECT_NE(wide.find("at most 100"), std::string::npos) << wide;
  options.window_side_px = 256;
  EXPECT_EQ(WindowRefusal(roi, options), "");
  EXPECT_FALSE(FrameFeatures(roi, 12, options).blob_found);  // flat: measured, no blob
}

TEST_F(SmallRecordingTest, FeaturesFromPngEqualFeaturesFromMemory) {
  const RecordingReader reader((dir_ / "recording").string());
  const FeatureOptions options;
  const FeatureMap from_png = RecordingFeatures(reader, options);
  ASSERT_EQ(from_png.size(), 5u);
  FeatureMap cache;
  for (size_t i = 0; i < images_.size(); ++i) {
    cache[static_cast<std::int64_t>(i)] = FrameFeatures(images_[i], 12, options);
    EXPECT_EQ(cache[static_cast<std::int64_t>(i)].e_rel,
              from_png.at(static_cast<std::int64_t>(i)).e_rel);
    EXPECT_EQ(cache[static_cast<std::int64_t>(i)].sigma,
              from_png.at(static_cast<std::int64_t>(i)).sigma);
  }
  // A cached entry is taken as is (the live run's in-memory frames).
  cache[2].e_rel = 42.0;
  cache.erase(4);
  const FeatureMap mixed = RecordingFeatures(reader, options, cache);
  EXPECT_EQ(mixed.at(2).e_rel, 42.0);
  EXPECT_EQ(mixed.at(4).e_rel, from_png.at(4).e_rel);

  const std::string a = (dir_ / "a.csv").string(), b = (dir_ / "b.csv").string();
  WriteFeaturesCsv(a, reader.rows(), from_png);
  WriteFeaturesCsv(b, reader.rows(), RecordingFeatures(reader, options, FeatureMap{{0, cache[0]}}));
  EXPECT_EQ(ReadAll(a), ReadAll(b));
  std::istringstream lines(ReadAll(a));
  std::string header, first;
  std::getline(lines, header);
  std::getline(lines, first);
  EXPECT_EQ(header.rfind("index,file,bracket,frame_in_bracket,role,exposure_us", 0), 0u);
  EXPECT_EQ(first.rfind("0,frames/000000.png,0,0,ref,8000,", 0), 0u) << first;
  int rows = 0;
  for (std::string line; std::getline(lines, line);) ++rows;
  EXPECT_EQ(rows, 4);  // plus the first: 5 frames
}

}  // namespace
}  // namespace irdist
