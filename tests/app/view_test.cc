// snap and view on the virtual rig (in process, GIGE): snap writes the frame and finds the blob
// where the rig's physics puts it; view refuses without a display and, under Xvfb when the
// machine has it, shows the live image with its overlay (checked on a screenshot).
#include "app/view.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <thread>

#include "app/errors.h"
#include "acquisition/camera.h"
#include "app/show.h"
#include "tests/loopback_gvcp.h"

extern char** environ;

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
  for (const char* step : {"--at: [", "homing the station", "IRED current to 490.0 mA",
                           "moving to slide 2000.0 mm", "at the pose"}) {
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

// Xvfb on display :97 for the life of the object (skips when the machine has no Xvfb).
class Xvfb {
 public:
  Xvfb() {
    for (const char* path : {"/usr/bin/Xvfb", "/usr/local/bin/Xvfb"}) {
      if (fs::exists(path)) binary_ = path;
    }
    if (binary_.empty()) return;
    std::vector<std::string> words = {binary_, ":97", "-screen", "0", "1024x768x24", "-nolisten",
                                      "tcp"};
    std::vector<char*> argv;
    for (std::string& w : words) argv.push_back(w.data());
    argv.push_back(nullptr);
    if (posix_spawn(&pid_, binary_.c_str(), nullptr, nullptr, argv.data(), environ) != 0) pid_ = -1;
    std::this_thread::sleep_for(std::chrono::seconds(1));
  }
  ~Xvfb() {
    if (pid_ > 0) {
      kill(pid_, SIGTERM);
      waitpid(pid_, nullptr, 0);
    }
  }
  Xvfb(const Xvfb&) = delete;
  Xvfb& operator=(const Xvfb&) = delete;
  bool running() const { return pid_ > 0; }

 private:
  std::string binary_;
  pid_t pid_ = -1;
};

TEST(View, ShowsTheLiveImageWithItsOverlayUnderXvfb) {
  Xvfb xvfb;
  if (!xvfb.running()) GTEST_SKIP() << "no Xvfb on this machine";
  setenv("DISPLAY", ":97", 1);
  testing::LoopbackGvcpLock lock;
  const std::string shot = Scratch("xvfb") + "/view.png";
  ViewArgs args;
  args.rig = VirtualRig();
  args.at = {2000.0, 20.0, 0.0, 490.0};
  args.frames = 5;
  args.time_scale = 50.0;
  args.screenshot = shot;
  std::ostringstream out, err;
  RunView(args, {out, err});
  const cv::Mat image = cv::imread(shot, cv::IMREAD_COLOR);
  ASSERT_FALSE(image.empty());
  EXPECT_EQ(image.cols, 768);  // the 256 px ROI, enlarged 3x for display
  // The ellipse is drawn in red and the window of the features in green around the centre.
  int red = 0, green = 0;
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x) {
      const cv::Vec3b p = image.at<cv::Vec3b>(y, x);
      red += p[2] == 255 && p[1] == 0 && p[0] == 0;
      green += p[1] == 255 && p[2] == 0 && p[0] == 0;
    }
  }
  EXPECT_GT(red, 20);
  EXPECT_GT(green, 20);
}

}  // namespace
}  // namespace irdist
