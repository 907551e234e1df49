// A bracket against the virtual rig (sim/): the frames carry the exposures requested, in order.
// The rig renders each frame from radiometry with the exposure latched for it, so the emitter's
// integrated signal in each frame must scale like the noise-free ground truth for its exposure.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "acquisition/aravis_camera.h"
#include "acquisition/bracket.h"
#include "sim/virtual_rig.h"
#include "tests/loopback_gvcp.h"

namespace irdist {
namespace {

// Signal of the frame above its background (the median gray level), in gray levels.
double SignalAboveBackground(const cv::Mat& image) {
  std::vector<std::uint16_t> values(image.begin<std::uint16_t>(), image.end<std::uint16_t>());
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  const double background = values[values.size() / 2];
  double sum = 0.0;
  for (auto it = image.begin<std::uint16_t>(); it != image.end<std::uint16_t>(); ++it) {
    if (*it > background + 8) sum += *it - background;
  }
  return sum;
}

TEST(BracketVirtualRig, FiveExposureBracketCarriesTheRequestedExposuresInOrder) {
  testing::LoopbackGvcpLock lock;
  sim::VirtualRigOverrides overrides;
  overrides.serial = "IRDVACQ1";
  overrides.seed = 7;
  auto rig = sim::VirtualRig::Start(IRDIST_SOURCE_DIR "/recipes/rigs/virtual.yaml", overrides);
  const double slide_mm = 1500.0;
  const double bias_ma = 500.0;
  rig->world().SetPose(slide_mm, 0.0, 0.0, false);
  rig->world().SetCurrent(bias_ma);

  auto camera = AravisCamera::Open(rig->Info().camera_address, rig->Info().serial);
  CameraSettings settings;
  settings.pixel_format = "Mono12";
  settings.trigger_source = "Software";
  camera->Configure(settings);

  BracketOptions options;
  // Neighbours differ by >= 1.5x, so a frame taken with its neighbour's exposure cannot pass.
  options.exposures_us = {8000.0, 24000.0, 12000.0, 36000.0, 16000.0};
  options.trigger_source = "Software";
  BracketCapture capture(*camera, options);
  const BracketResult result = capture.Capture([&](int) { camera->SoftwareTrigger(); });
  camera->StopStream();
  ASSERT_TRUE(result.complete) << result.BriefReport() << " / " << capture.stats().BriefReport();
  ASSERT_EQ(result.frames.size(), 5u);

  // Each frame's signal, relative to the first frame's, must be nearest (in log ratio) to the
  // ground truth of its own exposure among all the bracket's exposures, and within 15% of it (the
  // sensor model is not perfectly linear, so exact proportionality is not expected).
  std::vector<double> truth_ratio;
  const double truth0 =
      rig->Describe(slide_mm, 0.0, 0.0, bias_ma, options.exposures_us[0]).signal_e;
  for (double exposure_us : options.exposures_us) {
    const auto truth = rig->Describe(slide_mm, 0.0, 0.0, bias_ma, exposure_us);
    EXPECT_FALSE(truth.saturated);
    truth_ratio.push_back(truth.signal_e / truth0);
  }
  const double signal0 = SignalAboveBackground(result.frames[0].image);
  ASSERT_GT(signal0, 0.0);
  for (size_t i = 0; i < result.frames.size(); ++i) {
    const BracketFrame& frame = result.frames[i];
    EXPECT_NEAR(frame.actual_exposure_us, options.exposures_us[i], 1.0);
    const double measured = SignalAboveBackground(frame.image) / signal0;
    size_t nearest = 0;
    for (size_t k = 1; k < truth_ratio.size(); ++k) {
      if (std::fabs(std::log(measured / truth_ratio[k])) <
          std::fabs(std::log(measured / truth_ratio[nearest]))) {
        nearest = k;
      }
    }
    EXPECT_EQ(nearest, i) << "frame " << i << " looks taken with " << options.exposures_us[nearest]
                          << " us";
    EXPECT_NEAR(measured, truth_ratio[i], 0.15 * truth_ratio[i]) << "frame " << i;
  }
  EXPECT_EQ(capture.stats().lost, 0);
  camera.reset();
  rig->Stop();
}

}  // namespace
}  // namespace irdist
