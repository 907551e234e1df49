// snap and view on the virtual rig (in process, GIGE): snap writes the frame and finds the blob
// where the rig's physics puts it; view refuses without a display and, under Xvfb when the
// machine has it, shows the live image with its overlay, the whole sensor with the ROI drawn and
// saturated pixels marked (checked on screenshots).
#include "app/live/view.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <thread>

#include "acquisition/camera.h"
#include "app/inputs/errors.h"
#include "app/display/show.h"
#include "app/display/view_layout.h"
#include "tests/loopback_gvcp.h"
#include "tests/xvfb.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;

std::string Scratch(const std::string& name) {
  const std::string dir = std::string(IRDIST_BINARY_DIR) + "/tests/app/scratch/view-" + name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string VirtualRig() { return std::string(IRDIST_SOURCE_DIR) + "/recipes/rigs/virtual.yaml"; }

TEST(Snap, SavesTheFrameAndFindsTheBlobOnTheAxis) {
  testing::LoopbackGvcpLock lock;
  const std::string png = Scratch("snap") + "/frame.png";
  SnapArgs args;
  args.rig = VirtualRig();
  args.out = png;
  args.at = {2000.0, 0.0, 0.0, 490.0};
  args.time_scale = 50.0;
  std::ostringstream out, err;
  RunSnap(args, {out, err});
  const cv::Mat image = cv::imread(png, cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(image.empty()) << out.str();
  EXPECT_EQ(image.cols, 256);  // the rig's ROI
  EXPECT_EQ(image.rows, 256);
  EXPECT_EQ(image.depth(), CV_16U);
  // The IRED on the optical axis images at the sensor's centre (639.5, 511.5).
  EXPECT_NE(out.str().find("Blob at (639."), std::string::npos) << out.str();
  EXPECT_NE(out.str().find("Suggested roi_px: [512, 384, 256, 256]"), std::string::npos)
      << out.str();
  // Beside it, an 8-bit preview for people: black = background, white = the brightest pixel.
  const cv::Mat preview =
      cv::imread(png.substr(0, png.size() - 4) + ".preview.png", cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(preview.empty()) << out.str();
  EXPECT_EQ(preview.depth(), CV_8U);
  EXPECT_EQ(preview.size(), image.size());
  double lowest = 0.0, highest = 0.0;
  cv::minMaxLoc(preview, &lowest, &highest);
  EXPECT_EQ(highest, 255.0);
  EXPECT_LT(cv::mean(preview(cv::Rect(0, 0, 32, 32)))[0], 5.0);  // a corner of the background
  EXPECT_NE(out.str().find(".preview.png"), std::string::npos) << out.str();
  // --at says each step while the station homes, moves and the current settles.
  // The camera is put back as it was found when snap is done (camera.restore_after's default).
  for (const char* step : {"--at: [", "homing the station", "IRED current to 490.0 mA",
                           "moving to slide 2000.0 mm", "at the pose",
                           "The camera was put back as it was found."}) {
    EXPECT_NE(err.str().find(step), std::string::npos) << step << "\n" << err.str();
  }
}

// With the IRED off nothing is found: the message names the ROI with its numbers, how to widen it,
// and snap's own flags.
TEST(Snap, NoBlobSaysWhereItLookedAndHowToWidenIt) {
  testing::LoopbackGvcpLock lock;
  SnapArgs args;
  args.rig = VirtualRig();
  args.out = Scratch("snap-dark") + "/frame.png";
  args.at = {2000.0, 0.0, 0.0, 0.0};
  args.time_scale = 50.0;
  std::ostringstream out, err;
  RunSnap(args, {out, err});
  const std::string text = out.str();
  EXPECT_NE(text.find("No blob found in the rig's roi_px [512, 384, 256, 256]"), std::string::npos)
      << text;
  EXPECT_NE(text.find("remove camera.roi_px from " + VirtualRig()), std::string::npos) << text;
  EXPECT_NE(text.find("--exposure-ms"), std::string::npos) << text;
  EXPECT_NE(text.find("snap --at"), std::string::npos) << text;
}

// An exposure the camera cannot take is named by snap's flag, not by a recipe's exposures.
TEST(Snap, AnExposureOutsideTheCamerasRangeNamesExposureMs) {
  testing::LoopbackGvcpLock lock;
  SnapArgs args;
  args.rig = VirtualRig();
  args.out = Scratch("snap-exposure") + "/frame.png";
  args.exposure_ms = 1e9;
  args.time_scale = 50.0;
  std::ostringstream out, err;
  try {
    RunSnap(args, {out, err});
    ADD_FAILURE() << "an exposure of 1e9 ms was accepted";
  } catch (const CameraError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("--exposure-ms"), std::string::npos) << what;
    EXPECT_EQ(what.find("recipe"), std::string::npos) << what;
  }
}

// snap and view never replace a file unasked, never write through a link, and write PNG only;
// each refused before the camera starts.
TEST(Snap, RefusesAnExistingFileALinkAndAnotherFormatBeforeTheCamera) {
  const std::string dir = Scratch("snap-refusals");
  std::ostringstream out, err;
  SnapArgs snap;
  snap.rig = VirtualRig();
  snap.out = dir + "/frame.jpg";
  try {
    RunSnap(snap, {out, err});
    FAIL() << "snap wrote a JPEG";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("supported format: .png"), std::string::npos) << e.what();
  }
  snap.out = dir + "/recorded.png";
  std::ofstream(snap.out) << "a recorded frame";
  EXPECT_THROW(RunSnap(snap, {out, err}), RunFolderError);
  fs::create_symlink(dir + "/recorded.png", dir + "/link.png");
  snap.out = dir + "/link.png";
  snap.force = true;
  EXPECT_THROW(RunSnap(snap, {out, err}), RunFolderError);
  // Regression: a missing folder was found only after the station had moved to --at.
  snap.out = dir + "/missing/dir/x.png";
  snap.at = {2000.0, 0.0, 0.0, 490.0};
  try {
    RunSnap(snap, {out, err});
    FAIL() << "snap accepted an --out in a missing folder";
  } catch (const RunFolderError& e) {
    EXPECT_NE(std::string(e.what()).find(dir + "/missing/dir does not exist"), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(err.str().find("--at:"), std::string::npos) << "the station moved: " << err.str();
  ViewArgs view;
  view.rig = VirtualRig();
  view.screenshot = dir + "/recorded.png";
  try {
    RunView(view, {out, err});
    FAIL() << "view would replace an existing screenshot";
  } catch (const RunFolderError& e) {
    EXPECT_NE(std::string(e.what()).find("--force"), std::string::npos) << e.what();
  }
  view.screenshot = dir + "/view.tiff";
  EXPECT_THROW(RunView(view, {out, err}), UsageError);
  std::ifstream in(dir + "/recorded.png");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text, "a recorded frame");
}

TEST(View, WithoutADisplaySaysSo) {
  unsetenv("DISPLAY");
  unsetenv("WAYLAND_DISPLAY");
  ViewArgs args;
  args.rig = VirtualRig();
  std::ostringstream out, err;
  EXPECT_THROW(RunView(args, {out, err}), DisplayError);
}

int CountColour(const cv::Mat& bgr, const cv::Scalar& colour) {
  cv::Mat mask;
  cv::inRange(bgr, colour, colour, mask);
  return cv::countNonZero(mask);
}

// The one Xvfb of this test process: OpenCV's window system connects to one display for the
// process's life, so every view here shares it (stopped at exit).
const testing::Xvfb& SharedXvfb() {
  static const testing::Xvfb xvfb;
  return xvfb;
}

// view for `frames` frames under Xvfb; the screenshot, or an empty image (no Xvfb).
cv::Mat ViewUnderXvfb(const std::string& name, ViewArgs args, std::string* output) {
  if (!SharedXvfb().running()) return {};
  setenv("DISPLAY", SharedXvfb().display().c_str(), 1);
  testing::LoopbackGvcpLock lock;
  const std::string shot = Scratch(name) + "/view.png";
  args.rig = VirtualRig();
  args.time_scale = 50.0;
  args.screenshot = shot;
  std::ostringstream out, err;
  RunView(args, {out, err});
  *output = out.str();
  return cv::imread(shot, cv::IMREAD_COLOR);
}

TEST(View, ShowsTheLiveImageWithItsOverlayUnderXvfb) {
  ViewArgs args;
  args.at = {2000.0, 20.0, 0.0, 490.0};
  args.frames = 5;
  std::string output;
  const cv::Mat image = ViewUnderXvfb("xvfb", args, &output);
  if (!SharedXvfb().running()) GTEST_SKIP() << "no Xvfb on this machine";
  ASSERT_FALSE(image.empty());
  EXPECT_LE(image.cols, 1024);  // laid out to the window, within the 1024 x 768 screen
  EXPECT_LE(image.rows, 768);
  // The ellipse is drawn in red and the window of the features in green around the centre; no
  // pixel saturates at this pose, and the ROI is shown (no cyan outline).
  EXPECT_GT(CountColour(image, kEllipseColour), 20);
  EXPECT_GT(CountColour(image, kWindowColour), 20);
  EXPECT_EQ(CountColour(image, kSaturatedColour), 0);
  EXPECT_EQ(CountColour(image, kRoiColour), 0);
  // On exit view states what it showed last: the region and the focus figure (no model: the
  // edge width).
  EXPECT_NE(output.find("roi_px [512, 384, 256, 256]"), std::string::npos) << output;
  EXPECT_NE(output.find("focus: edge width"), std::string::npos) << output;
}

TEST(View, WholeSensorDrawsTheRoiAndMarksSaturatedPixels) {
  ViewArgs args;
  args.at = {1500.0, 0.0, 0.0, 600.0};
  args.exposure_ms = 80.0;  // the IRED saturates the camera at 1.5 m, full current, 80 ms
  args.whole_sensor = true;
  args.frames = 3;
  std::string output;
  const cv::Mat image = ViewUnderXvfb("whole", args, &output);
  if (!SharedXvfb().running()) GTEST_SKIP() << "no Xvfb on this machine";
  ASSERT_FALSE(image.empty());
  EXPECT_GT(CountColour(image, kRoiColour), 400);        // the rig's roi_px outline
  EXPECT_GT(CountColour(image, kSaturatedColour), 10);   // the saturated blob
  EXPECT_NE(output.find("whole sensor 1280 x 1024"), std::string::npos) << output;
  EXPECT_NE(output.find("saturated pixels (magenta)"), std::string::npos) << output;
  EXPECT_NE(output.find("shorten --exposure-ms"), std::string::npos) << output;
}

}  // namespace
}  // namespace irdist
