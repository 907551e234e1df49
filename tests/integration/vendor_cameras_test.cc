// The built irdist binary on real vendors' GenICam files (Basler acA1300-60gm, FLIR Blackfly S
// BFS-PGE-19S4M) served by Aravis's fake camera (tests/acquisition/vendor_camera.h). Both declare
// ChunkExposureTime, which the fake camera never sends: irdist must fall back to reading each
// exposure back, say so once, and capture every frame.
// 1. `irdist snap` on a hardware rig file naming the fake camera by address: a complete PNG.
// 2. `irdist calibrate` of a 2-pose recipe (`after: none`: the fake camera's test pattern shows no
//    IRED, so nothing is fitted) on the same camera and a virtual irdist station: every bracket
//    recorded complete and `irdist check` clean on the recording.
// The station is the virtual rig's station emulator, run by this test on a pty: `irdist sim` would
// also serve its own camera on 127.0.0.1's GVCP port 3956, which the fake camera holds.
#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "sim/station_emulator.h"
#include "sim/world.h"
#include "tests/acquisition/vendor_camera.h"
#include "tests/integration/run_helpers.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;
using testing::ReadAll;
using testing::RunIrdist;
using testing::WriteAll;

struct VendorFile {
  const char* fixture;
  const char* serial;
  const char* pixel_format;  // the rig file's
};

void PrintTo(const VendorFile& vendor, std::ostream* out) { *out << vendor.fixture; }

const VendorFile kBasler{"basler_aca1300_60gm", "IRDIBA01", "Mono12"};
const VendorFile kFlir{"flir_bfs_pge_19s4m", "IRDIFL01", "Mono12p"};

constexpr const char* kFallback = "without its ChunkExposureTime chunk";

// The warnings of the read-back fallback in a command's output (a run's closing capture summary
// restates it; that is no second warning).
int FallbackWarnings(const std::string& output) {
  std::istringstream lines(output);
  int n = 0;
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("warning: ", 0) == 0 && line.find(kFallback) != std::string::npos) ++n;
  }
  return n;
}

// A hardware rig: the fake camera by address, fired by software trigger; a composed station of one
// irdist_station on `station_port` (motion and source; the camera triggers itself).
std::string RigFile(const VendorFile& vendor, const std::string& station_port) {
  return std::string("name: vendor-") + vendor.serial + R"(
kind: hardware
camera:
  id: "127.0.0.1"
  pixel_format: )" + vendor.pixel_format + R"(
  trigger_source: Software
  frame_timeout_ms: 1000
  readout_ms: 5
  roi_px: [0, 0, 256, 128]
station:
  limits: {slide_mm: [1000, 3500], pan_deg: [-45, 45], tilt_deg: [-45, 45], bias_ma: [0, 600]}
  roles:
    motion: [box]
    source: box
    trigger: camera_software
  devices:
    box:
      driver: irdist_station
      port: )" + station_port + "\n";
}

// Two poses, one current, a reference and two measurement exposures; recorded only.
std::string TwoPoseRecipe() {
  return R"(name: vendor-two-poses
rig: rig.yaml
after: none
axes:
  slide_mm: [1500, 2000]
  theta_deg: [0]
  bias_ma: [500]
bracket:
  t_ref_ms: 2
  t_meas_ms: [4, 6]
)";
}

class VendorCameras : public ::testing::TestWithParam<VendorFile> {
 protected:
  void SetUp() override {
    dir_ = testing::ScratchDir(std::string("vendor-cameras-") + GetParam().fixture);
  }
  std::string dir_;
};

// snap: one complete frame of the ROI's size, the read-back fallback said once.
TEST_P(VendorCameras, SnapWritesACompleteFrame) {
  const VendorFile& vendor = GetParam();
  testing::VendorFakeCamera fake(vendor.fixture, vendor.serial);
  WriteAll(dir_ + "/rig.yaml", RigFile(vendor, "/dev/null"));  // snap opens no station
  std::string output;
  const std::string png = dir_ + "/snap.png";
  ASSERT_EQ(RunIrdist({"snap", "--rig", dir_ + "/rig.yaml", "--out", png, "--exposure-ms", "2"},
                      dir_ + "/snap.log", &output),
            0)
      << output;
  EXPECT_NE(output.find("(256 x 128, "), std::string::npos) << output;
  EXPECT_EQ(FallbackWarnings(output), 1) << output;
  // The whole frame, 16 bit per pixel (12 bit of the camera's). The fake camera's test pattern
  // is black with these files (its pattern follows registers of its own, which they do not map).
  const cv::Mat image = cv::imread(png, cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(image.empty()) << png;
  EXPECT_EQ(image.cols, 256);
  EXPECT_EQ(image.rows, 128);
  EXPECT_EQ(image.type(), CV_16UC1);
}

// A 2-pose calibration recorded through the fake camera and a virtual station: 2 brackets of 3
// frames, the fallback said once, the recording checked clean.
TEST_P(VendorCameras, TinyCalibrationRecordsEveryBracket) {
  const VendorFile& vendor = GetParam();
  testing::VendorFakeCamera fake(vendor.fixture, vendor.serial);
  sim::World world(50.0);
  sim::StationEmulator station(world, sim::EmulatorOptions{});
  WriteAll(dir_ + "/rig.yaml", RigFile(vendor, station.Start()));
  WriteAll(dir_ + "/recipe.yaml", TwoPoseRecipe());
  std::string output;
  ASSERT_EQ(RunIrdist({"calibrate", dir_ + "/recipe.yaml", "--out", dir_ + "/cal",
                       "--allow-nonlinear"},
                      dir_ + "/calibrate.log", &output, std::chrono::seconds(180)),
            0)
      << output;
  EXPECT_EQ(FallbackWarnings(output), 1) << output;
  EXPECT_NE(output.find("Capture: brackets 2 (failed 0), frames requested 6, received 6"),
            std::string::npos)
      << output;
  const std::string recording = dir_ + "/cal/recording";
  // frames.csv: a header and 2 brackets x 3 frames.
  EXPECT_EQ(testing::CountLines(recording + "/frames.csv"), 1 + 2 * 3) << ReadAll(recording +
                                                                                  "/frames.csv");
  ASSERT_EQ(RunIrdist({"check", recording}, dir_ + "/check.log", &output), 0) << output;
  EXPECT_NE(output.find("recording complete, 6 frames, 2/2 brackets complete, 0 errors, 0 warnings"),
            std::string::npos)
      << output;
}

INSTANTIATE_TEST_SUITE_P(Vendors, VendorCameras, ::testing::Values(kBasler, kFlir),
                         [](const ::testing::TestParamInfo<VendorFile>& info) {
                           return std::string(info.param.fixture);
                         });

}  // namespace
}  // namespace irdist
