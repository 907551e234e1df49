// snap on the virtual rig (in process, GIGE): it writes the frame and its preview and finds the
// blob where the rig's physics puts it; what it says when it finds none; its refusals.
#include "app/live/snap_command.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <string>

#include "acquisition/camera.h"
#include "app/inputs/errors.h"
#include "tests/loopback_gvcp.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;

std::string Scratch(const std::string& name) {
  const std::string dir = std::string(IRDIST_BINARY_DIR) + "/tests/app/scratch/snap-" + name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string VirtualRig() { return std::string(IRDIST_SOURCE_DIR) + "/recipes/rigs/virtual.yaml"; }

TEST(Snap, SavesTheFrameAndFindsTheBlobOnTheAxis) {
  testing::LoopbackGvcpLock lock;
  const std::string png = Scratch("frame") + "/frame.png";
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
  args.out = Scratch("dark") + "/frame.png";
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
  args.out = Scratch("exposure") + "/frame.png";
  args.exposure_ms = 1e9;  // beyond any camera's (base/bounds.h): refused before the camera
  args.time_scale = 50.0;
  std::ostringstream out, err;
  try {
    RunSnap(args, {out, err});
    ADD_FAILURE() << "an exposure of 1e9 ms was accepted";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("--exposure-ms"), std::string::npos) << e.what();
  }
  args.exposure_ms = 5000.0;  // inside the bounds, beyond the virtual camera's 1 s
  try {
    RunSnap(args, {out, err});
    ADD_FAILURE() << "an exposure of 5000 ms was accepted";
  } catch (const CameraError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("--exposure-ms"), std::string::npos) << what;
    EXPECT_EQ(what.find("recipe"), std::string::npos) << what;
  }
}

// snap never replaces a file unasked, never writes through a link, and writes PNG only; each
// refused before the camera starts.
TEST(Snap, RefusesAnExistingFileALinkAndAnotherFormatBeforeTheCamera) {
  const std::string dir = Scratch("refusals");
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
}

}  // namespace
}  // namespace irdist
