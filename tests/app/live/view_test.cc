// view on the virtual rig (in process, GIGE): it refuses without a display and, under Xvfb when
// the machine has it, shows the live image with its overlay, the whole sensor with the ROI drawn
// and saturated pixels marked (checked on screenshots). snap is in snap_command_test.cc.
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

// view never replaces a screenshot unasked and writes PNG only; each refused before the camera
// starts.
TEST(View, RefusesAnExistingScreenshotAndAnotherFormatBeforeTheCamera) {
  const std::string dir = Scratch("refusals");
  std::ostringstream out, err;
  std::ofstream(dir + "/recorded.png") << "a recorded frame";
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
