// Single exposures of the virtual rig's camera (in process, GIGE), as snap and view take them:
// a frame of the rig's ROI at the requested exposure with the IRED where the rig's physics puts
// it, its signal doubling with the exposure; and the signal line both commands print.
#include "app/live/single_exposure.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "tests/loopback_gvcp.h"
#include "tests/virtual_rig_with.h"

namespace irdist {
namespace {

std::string VirtualRig() { return std::string(IRDIST_SOURCE_DIR) + "/recipes/rigs/virtual.yaml"; }

// Peak and background are fractions of full scale, printed as percentages.
TEST(LevelLine, GivesPeakAndBackgroundInPercentOfFullScaleAndSaturatedPixels) {
  Features f;
  f.peak = 0.5;
  f.background = 0.0125;
  f.saturated_pixels = 3;
  EXPECT_EQ(LevelLine(f), "peak 50.0% of full scale, background 1.25%, saturated px 3");
}

// The median of a frame: its background (the blob covers a few hundred of its 65536 pixels).
double Median(const cv::Mat& image) {
  std::vector<std::uint16_t> values(image.begin<std::uint16_t>(), image.end<std::uint16_t>());
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  return values[values.size() / 2];
}

// The IRED on the optical axis images at the sensor's centre (639.5, 511.5), in the rig's
// 256 x 256 roi_px at [512, 384] near (127.5, 127.5); twice the exposure collects twice the light
// above the background (a linear sensor, far from saturation at 2 m).
TEST(SingleExposure, GivesTheRoiFrameWithTheBlobOnTheAxisAndSignalProportionalToExposure) {
  testing::LoopbackGvcpLock lock;
  std::ostringstream err;
  std::unique_ptr<LiveCamera> live =
      OpenForSingleExposures(VirtualRig(), {2000.0, 0.0, 0.0, 490.0}, 8.0, 50.0, err);
  const cv::Mat short_frame = SingleExposure(*live, 4.0, err).Next().clone();
  const cv::Mat long_frame = SingleExposure(*live, 8.0, err).Next().clone();
  ASSERT_EQ(short_frame.size(), cv::Size(256, 256));
  ASSERT_EQ(short_frame.type(), CV_16UC1);
  cv::Point brightest;
  double short_peak = 0.0, long_peak = 0.0;
  cv::minMaxLoc(short_frame, nullptr, &short_peak, nullptr, &brightest);
  cv::minMaxLoc(long_frame, nullptr, &long_peak);
  EXPECT_NEAR(brightest.x, 127.5, 3.0);
  EXPECT_NEAR(brightest.y, 127.5, 3.0);
  ASSERT_LT(long_peak, 0.9 * ((1 << live->bit_depth()) - 1)) << "saturated: the test's premise";
  const double short_signal = cv::sum(short_frame)[0] - Median(short_frame) * short_frame.total();
  const double long_signal = cv::sum(long_frame)[0] - Median(long_frame) * long_frame.total();
  ASSERT_GT(short_signal, 0.0);
  EXPECT_NEAR(long_signal / short_signal, 2.0, 0.3);
}

// A camera whose exposure chunks stop coming: the capture's notice (each exposure read back from
// then on) reaches the stream the command gave, once, and nothing is lost.
TEST(SingleExposure, TheCapturesNoticeGoesToTheCommandsStreamOnce) {
  testing::LoopbackGvcpLock lock;
  std::ostringstream err;
  std::unique_ptr<LiveCamera> live = OpenForSingleExposures(
      testing::VirtualRigWithCameraKeys("chunks-stop", "    drop_exposure_chunks_from_frame: 4\n"),
      {2000.0, 0.0, 0.0, 490.0}, 8.0, 50.0, err);
  SingleExposure single(*live, 8.0, err);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(single.Next().size(), cv::Size(256, 256));
  const std::string notices = err.str();
  const std::string notice = "came without its ChunkExposureTime chunk";
  const std::size_t at = notices.find(notice);
  ASSERT_NE(at, std::string::npos) << notices;
  EXPECT_NE(notices.rfind("warning: ", at), std::string::npos) << notices;
  EXPECT_EQ(notices.find(notice, at + 1), std::string::npos) << notices;
}

}  // namespace
}  // namespace irdist
