// The scene pass's noise model and defect pixels (estimator/scene_defects.cc), through its
// estimator-internal header.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "estimator/scene.h"
#include "estimator/scene_internal.h"

namespace irdist::scene {
namespace {

// A flat Mono12 frame at `level` with Gaussian noise of `sd` DN (no noise when sd is 0).
cv::Mat Flat(int side, double level, double sd, unsigned seed = 7) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  cv::Mat out(side, side, CV_16UC1);
  for (int y = 0; y < side; ++y) {
    for (int x = 0; x < side; ++x) {
      out.at<std::uint16_t>(y, x) = static_cast<std::uint16_t>(std::lround(level + sd * noise(rng)));
    }
  }
  return out;
}

cv::Mat Median3(const cv::Mat& image) {
  cv::Mat m;
  cv::medianBlur(image, m, 3);
  return m;
}

// EMVA 1288: var = read^2 + gain (g - background); no shot noise below the background.
TEST(SceneNoiseModel, SdIsReadAndShotNoiseInQuadrature) {
  NoiseModel n;
  n.background = 100.0;
  n.read_sd = 2.0;
  n.shot_gain = 0.5;
  EXPECT_DOUBLE_EQ(n.Sd(100.0), 2.0);
  EXPECT_DOUBLE_EQ(n.Sd(132.0), std::sqrt(4.0 + 16.0));
  EXPECT_DOUBLE_EQ(n.Sd(50.0), 2.0);
}

// The background is the frame's median, the read noise the sd of its pixels (from neighbours'
// differences); a noise-free frame still has half a gray level of quantisation.
TEST(SceneNoiseModel, BackgroundAndReadNoiseOfAFlatFrame) {
  const NoiseModel noisy = MeasureBackgroundNoise(Flat(256, 200.0, 3.0), 12);
  EXPECT_NEAR(noisy.background, 200.0, 0.2);
  EXPECT_NEAR(noisy.read_sd, 3.0, 0.25);
  const NoiseModel clean = MeasureBackgroundNoise(Flat(64, 321.0, 0.0), 12);
  EXPECT_NEAR(clean.background, 321.0, 1e-9);
  EXPECT_EQ(clean.read_sd, 0.5);
}

// A plateau of 2000 DN above a 100 DN background whose variance is 4 + 1.0 x 2000 DN^2: the shot
// gain is 1 DN per DN (each frame's robust spread of ~2000 plateau pixels scatters by some 6 %:
// the mean of 8 frames). Without a plateau, the fallback (given at 12 bits) scaled to the depth.
TEST(SceneNoiseModel, ShotGainFromThePlateauOrTheFallback) {
  std::mt19937_64 rng(11);
  std::normal_distribution<double> unit(0.0, 1.0);
  double sum = 0.0;
  constexpr int kFrames = 8;
  for (int frame = 0; frame < kFrames; ++frame) {
    cv::Mat image(128, 128, CV_16UC1);
    for (int y = 0; y < 128; ++y) {
      for (int x = 0; x < 128; ++x) {
        const bool on = std::hypot(x - 64.0, y - 64.0) < 30.0;
        const double level = on ? 2100.0 : 100.0;
        const double sd = std::sqrt(4.0 + 1.0 * (level - 100.0));
        image.at<std::uint16_t>(y, x) =
            static_cast<std::uint16_t>(std::lround(level + sd * unit(rng)));
      }
    }
    NoiseModel n;
    n.background = 100.0;
    n.read_sd = 2.0;
    MeasureShotGain(image, Median3(image), 12, 0.39, &n);
    EXPECT_NEAR(n.shot_gain, 1.0, 0.2) << "frame " << frame;
    sum += n.shot_gain;
  }
  EXPECT_NEAR(sum / kFrames, 1.0, 0.06);

  const cv::Mat flat = Flat(64, 100.0, 2.0);
  NoiseModel dark = MeasureBackgroundNoise(flat, 12);
  MeasureShotGain(flat, Median3(flat), 12, 0.39, &dark);
  EXPECT_DOUBLE_EQ(dark.shot_gain, 0.39);
  MeasureShotGain(flat, Median3(flat), 10, 0.39, &dark);
  EXPECT_DOUBLE_EQ(dark.shot_gain, 0.39 * 1023.0 / 4095.0);
}

// On a flat frame of 3 DN noise: a hot pixel, a dead one and a pair of hot neighbours are found,
// nothing else is; a one-pixel dark line (a cable's shadow) is not a defect, nor is a pixel on
// the frame's border (it has no 8 neighbours).
TEST(SceneDefectPixels, FindsOutliersButNotLinesOrBorders) {
  cv::Mat image = Flat(96, 500.0, 3.0);
  image.at<std::uint16_t>(20, 30) = 700;
  image.at<std::uint16_t>(40, 50) = 300;
  image.at<std::uint16_t>(60, 20) = 650;
  image.at<std::uint16_t>(60, 21) = 660;
  image.at<std::uint16_t>(0, 10) = 900;
  for (int y = 0; y < 96; ++y) image.at<std::uint16_t>(y, 70) = 380;
  NoiseModel n;
  n.background = 500.0;
  n.read_sd = 3.0;
  const cv::Mat mask = DetectDefects(image, Median3(image), n, SceneOptions());
  std::vector<cv::Point> found;
  cv::findNonZero(mask, found);
  EXPECT_EQ(found, (std::vector<cv::Point>{{30, 20}, {50, 40}, {20, 60}, {21, 60}}));
}

// The known map is in sensor coordinates: the frame at roi_origin sees each pixel moved by it,
// and pixels off the frame are not set.
TEST(SceneDefectPixels, KnownMapIsPlacedByTheFramesOrigin) {
  DefectMap map;
  map.sensor_px = {{105, 210}, {100, 200}, {99, 200}, {132, 205}, {110, 232}};
  cv::Mat mask = cv::Mat::zeros(32, 32, CV_8U);
  AddKnownDefects(map, cv::Point(100, 200), &mask);
  std::vector<cv::Point> set;
  cv::findNonZero(mask, set);
  EXPECT_EQ(set, (std::vector<cv::Point>{{0, 0}, {5, 10}}));
}

// Each masked pixel takes the median of its unmasked neighbours (an even count: the mean of the
// middle two), computed from the frame before any replacement; with every neighbour masked, the
// median of all of them. Each replaced pixel is listed.
TEST(SceneDefectPixels, ReplacedByTheMedianOfGoodNeighbours) {
  cv::Mat image = (cv::Mat_<std::uint16_t>(4, 4) << 10, 20, 30, 40,
                                                    50, 999, 70, 80,
                                                    90, 100, 0, 120,
                                                    1, 2, 3, 4);
  cv::Mat mask = cv::Mat::zeros(4, 4, CV_8U);
  mask.at<std::uint8_t>(1, 1) = 255;
  mask.at<std::uint8_t>(2, 2) = 255;
  std::vector<cv::Point> where = {{9, 9}};
  ReplaceDefects(mask, &image, &where);
  // (1, 1): neighbours 10 20 30 50 70 90 100 (0 masked): median 50.
  EXPECT_EQ(image.at<std::uint16_t>(1, 1), 50);
  // (2, 2): neighbours 70 80 100 120 2 3 4 (999 masked): median 70.
  EXPECT_EQ(image.at<std::uint16_t>(2, 2), 70);
  EXPECT_EQ(where, (std::vector<cv::Point>{{9, 9}, {1, 1}, {2, 2}}));

  // A 2 x 2 frame all masked: each pixel the median of its 3 (masked) neighbours' original
  // values; with two masked, the mean of the two good ones.
  cv::Mat corner = (cv::Mat_<std::uint16_t>(2, 2) << 7, 100, 40, 10);
  cv::Mat all = cv::Mat(2, 2, CV_8U, cv::Scalar(255));
  std::vector<cv::Point> replaced;
  ReplaceDefects(all, &corner, &replaced);
  EXPECT_EQ(corner.at<std::uint16_t>(0, 0), 40);   // 100 40 10
  EXPECT_EQ(corner.at<std::uint16_t>(0, 1), 10);   // 7 40 10
  EXPECT_EQ(corner.at<std::uint16_t>(1, 1), 40);   // 7 100 40
  EXPECT_EQ(replaced.size(), 4u);
  cv::Mat even = (cv::Mat_<std::uint16_t>(2, 2) << 7, 100, 40, 11);
  cv::Mat one = cv::Mat::zeros(2, 2, CV_8U);
  one.at<std::uint8_t>(0, 0) = 255;
  one.at<std::uint8_t>(1, 1) = 255;
  ReplaceDefects(one, &even, &replaced);
  EXPECT_EQ(even.at<std::uint16_t>(0, 0), 70);  // (100 + 40) / 2
}

}  // namespace
}  // namespace irdist::scene
