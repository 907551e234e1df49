// What `irdist view` draws, on synthetic frames: saturated pixels in magenta (also one alone on
// the reduced whole sensor), the rig's ROI drawn on the whole sensor, the zoom on the blob, text
// wrapped to the window's width, and the focus figure against a calibrated blur.
#include "app/display/view_layout.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <string>

#include "estimator/blur_model.h"
#include "estimator/features.h"

namespace irdist {
namespace {

constexpr int kFullScale12 = 4095;

// A 12-bit frame: background 100, a uniformly bright disc of radius `r` at (cx, cy) at `level`.
cv::Mat DiscFrame(cv::Size size, double cx, double cy, double r, int level) {
  cv::Mat image(size, CV_16UC1, cv::Scalar(100));
  cv::circle(image, cv::Point(static_cast<int>(cx), static_cast<int>(cy)), static_cast<int>(r),
             cv::Scalar(level), cv::FILLED);
  return image;
}

int CountColour(const cv::Mat& bgr, const cv::Scalar& colour, cv::Rect where = {}) {
  const cv::Mat part = where.area() > 0 ? bgr(where) : bgr;
  cv::Mat mask;
  cv::inRange(part, colour, colour, mask);
  return cv::countNonZero(mask);
}

TEST(ComposeView, PaintsSaturatedPixelsMagentaAndNothingElse) {
  cv::Mat image = DiscFrame({256, 256}, 128, 128, 10, 3000);
  ViewPanel panel;
  panel.image = image;
  panel.bit_depth = 12;
  EXPECT_EQ(CountColour(ComposeView(panel, {1024, 720}), kSaturatedColour), 0);
  image(cv::Rect(126, 126, 3, 3)).setTo(kFullScale12);  // 9 saturated pixels
  const cv::Mat view = ComposeView(panel, {1024, 720});
  // Enlarged by whole pixels (the 256 px ROI fits 2x beside the zoom): 9 x 4 pixels at least in
  // the frame, and more in the zoom.
  EXPECT_GE(CountColour(view, kSaturatedColour, cv::Rect(0, 0, 512, 512)), 36);
  EXPECT_GT(CountColour(view, kSaturatedColour, cv::Rect(512, 0, view.cols - 512, 300)), 36);
}

TEST(ComposeView, FitsTheWindowAndKeepsALoneSaturatedPixelOnTheWholeSensor) {
  cv::Mat image = DiscFrame({1280, 1024}, 640, 512, 10, 3000);
  image.at<std::uint16_t>(100, 1000) = kFullScale12;  // one saturated pixel, far from the blob
  ViewPanel panel;
  panel.image = image;
  panel.roi = cv::Rect(512, 384, 256, 256);
  panel.lines = {"a line", "another line"};
  const cv::Mat view = ComposeView(panel, {1024, 720});
  EXPECT_EQ(view.cols, 1024);
  EXPECT_LE(view.rows, 720);
  EXPECT_GE(CountColour(view, kSaturatedColour), 1);  // survives the reduction
  // The ROI's outline: cyan around a reduced 256 px square (scale = 720 px high / 1024 rows at
  // most), i.e. at least its perimeter at that scale.
  const double scale = std::min((1024.0 - 272.0) / 1280.0, 1.0);
  EXPECT_GE(CountColour(view, kRoiColour), static_cast<int>(4 * 256 * scale * 0.9));
}

TEST(ComposeView, ZoomsOnTheBlobWhereTheFeaturesPutIt) {
  const cv::Mat image = DiscFrame({256, 256}, 60, 190, 8, 3000);
  Features f;
  f.blob_found = true;
  f.centroid_px = {60, 190};
  f.ellipse_moments.valid = true;
  f.ellipse_moments.center_px = {60, 190};
  f.ellipse_moments.major_px = 16;
  f.ellipse_moments.minor_px = 16;
  f.roi = cv::Rect(28, 158, 64, 64);
  ViewPanel panel;
  panel.image = image;
  panel.features = &f;
  const cv::Mat view = ComposeView(panel, {1024, 720});
  // The zoom (right of the 512 px frame, below its caption) is stretched from the background to
  // the disc: its centre is the disc (white), its corners background (black).
  const int zoom_x = 512 + 8, zoom_y = 20;
  const cv::Vec3b centre = view.at<cv::Vec3b>(zoom_y + 128, zoom_x + 128);
  const cv::Vec3b corner = view.at<cv::Vec3b>(zoom_y + 2, zoom_x + 2);
  EXPECT_EQ(centre, cv::Vec3b(255, 255, 255));
  EXPECT_EQ(corner, cv::Vec3b(0, 0, 0));
  EXPECT_GT(CountColour(view, kEllipseColour), 20);  // the ellipse is drawn
  EXPECT_GT(CountColour(view, kWindowColour), 20);   // and the features' window
}

TEST(WrapText, EveryLineFitsAndNoWordIsLost) {
  std::string text;
  for (int i = 0; i < 60; ++i) text += "word" + std::to_string(i) + " ";
  text += std::string(200, 'x');  // one word wider than the window
  const std::vector<std::string> lines = WrapText(text, 400);
  ASSERT_GT(lines.size(), 3u);
  std::string joined;
  for (const std::string& line : lines) {
    int baseline = 0;
    EXPECT_LE(cv::getTextSize(line, cv::FONT_HERSHEY_SIMPLEX, 0.5, 1, &baseline).width, 400) << line;
    joined += line;
  }
  for (int i = 0; i < 60; ++i) {
    EXPECT_NE(joined.find("word" + std::to_string(i)), std::string::npos) << i;
  }
  EXPECT_NE(joined.find(std::string(200, 'x')), std::string::npos);
}

TEST(ComposeView, TextLinesAreWrappedInsideANarrowWindow) {
  ViewPanel panel;
  panel.image = DiscFrame({256, 256}, 128, 128, 10, 3000);
  panel.lines = {std::string(40, 'a') + " " + std::string(40, 'b') + " " + std::string(40, 'c')};
  const cv::Mat narrow = ComposeView(panel, {640, 480});
  EXPECT_EQ(narrow.cols, 640);
  // The text is drawn below the frame and the zoom (from y = 326): there, the last 8 columns (the
  // margin) stay black, and text is drawn.
  const cv::Rect text_area(0, 326, narrow.cols, narrow.rows - 326);
  cv::Mat gray;
  cv::cvtColor(narrow(text_area), gray, cv::COLOR_BGR2GRAY);
  EXPECT_EQ(cv::countNonZero(gray(cv::Rect(gray.cols - 8, 0, 8, gray.rows))), 0);
  EXPECT_GT(cv::countNonZero(gray > 128), 100);
}

Features UsableBlob(double blur_var_px2) {
  Features f;
  f.blob_found = true;
  f.blur_var_px2 = blur_var_px2;
  return f;
}

TEST(FocusTracker, ComparesTheBlurWithTheCalibratedBlurAtTheDistance) {
  BlurCalibration calibration;
  calibration.c0_px2 = 0.5 + 1.0 / 12.0;  // sigma 0.707 px at every distance, pixel area added
  calibration.noise_at_1m_px2 = 0.01;
  FocusTracker tracker(&calibration);
  // sigma 0.8485 px: +20% against 0.7071.
  const FocusFigure figure = tracker.Add(UsableBlob(0.72 + 1.0 / 12.0), 2500.0);
  ASSERT_TRUE(figure.valid && figure.calibrated);
  EXPECT_NEAR(figure.blur_sigma_px, std::sqrt(0.72), 1e-9);
  EXPECT_NEAR(figure.change, std::sqrt(0.72 / 0.5) - 1.0, 1e-9);
  EXPECT_NE(figure.Line().find("+20%"), std::string::npos) << figure.Line();
  EXPECT_NE(figure.Line().find("turn the focus ring"), std::string::npos);
  // Back at the calibrated blur (the running mean of the last frames follows).
  FocusFigure back;
  for (int i = 0; i < 5; ++i) back = tracker.Add(UsableBlob(0.5 + 1.0 / 12.0), 2500.0);
  EXPECT_NEAR(back.change, 0.0, 1e-9);
  EXPECT_NE(back.Line().find("as calibrated"), std::string::npos) << back.Line();
}

TEST(FocusTracker, WithoutAModelGivesTheEdgeWidthAndTheBestSeen) {
  FocusTracker tracker(nullptr);
  const FocusFigure sharp = tracker.Add(UsableBlob(0.25), 0.0);
  ASSERT_TRUE(sharp.valid);
  EXPECT_FALSE(sharp.calibrated);
  EXPECT_NEAR(sharp.edge_width_px, 2.0 * 1.2815516 * 0.5, 1e-6);  // 10-90% of a sd 0.5 edge
  FocusFigure blurred;
  for (int i = 0; i < 5; ++i) blurred = tracker.Add(UsableBlob(1.0), 0.0);
  EXPECT_NEAR(blurred.edge_width_px, 2.0 * 1.2815516, 1e-6);
  EXPECT_NEAR(blurred.best_edge_width_px, sharp.edge_width_px, 1e-9);
  EXPECT_NE(blurred.Line().find("best so far"), std::string::npos);
  // A frame without a usable blob gives no figure (none stale) and changes no history.
  Features saturated = UsableBlob(0.25);
  saturated.saturated_pixels = 3;
  EXPECT_FALSE(tracker.Add(saturated, 0.0).valid);
  EXPECT_NEAR(tracker.Add(UsableBlob(1.0), 0.0).edge_width_px, 2.0 * 1.2815516, 1e-6);
}

}  // namespace
}  // namespace irdist

namespace irdist {
namespace {

// The scene pass's findings are drawn where they are: a box around each defect pixel replaced
// (yellow), each other blob masked outlined (orange); nothing of either colour without them.
TEST(DrawFeatures, MarksTheDefectPixelsAndTheOtherBlobsTheScenePassFound) {
  Features f;
  f.blob_found = true;
  f.roi = cv::Rect(10, 10, 64, 64);
  cv::Mat view(256, 256, CV_8UC3, cv::Scalar(0, 0, 0));
  DrawFeatures(f, 2.0, &view);
  EXPECT_EQ(CountColour(view, kDefectColour), 0);
  EXPECT_EQ(CountColour(view, kOtherBlobColour), 0);
  f.scene.defect_px = {cv::Point(30, 40)};
  f.scene.other_blob_rects = {cv::Rect(80, 20, 10, 8)};
  DrawFeatures(f, 2.0, &view);
  // At 2x, pixel (30, 40) covers [60, 62) x [80, 82): its box is drawn around it.
  EXPECT_GT(CountColour(view, kDefectColour, cv::Rect(56, 76, 10, 10)), 8);
  EXPECT_EQ(CountColour(view, kDefectColour, cv::Rect(61, 81, 1, 1)), 0);  // the pixel stays seen
  EXPECT_GT(CountColour(view, kOtherBlobColour, cv::Rect(158, 38, 24, 20)), 40);
}

}  // namespace
}  // namespace irdist
