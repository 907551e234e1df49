// `irdist plan --suggest` on the virtual rig: the exposures it proposes, checked against the rig's
// own noise-free ground truth (sim::Renderer), not against the probe frames it measured.
#include <gtest/gtest.h>

#include <regex>
#include <sstream>

#include "sim/renderer.h"
#include "sim/rig_physics.h"
#include "tests/integration/run_helpers.h"
#include "tests/loopback_gvcp.h"

namespace irdist {
namespace {

std::vector<double> ParseList(const std::string& text) {
  std::vector<double> values;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) values.push_back(std::stod(item));
  return values;
}

TEST(Suggest, ProposesExposuresThatNeitherSaturateNorDrown) {
  const std::string dir = testing::ScratchDir("suggest");
  const std::string recipe = std::string(IRDIST_SOURCE_DIR) + "/recipes/smoke-calibration.yaml";
  testing::LoopbackGvcpLock lock;
  std::string output;
  ASSERT_EQ(testing::RunIrdist({"plan", recipe, "--suggest", "--out", dir + "/run", "--time-scale",
                                "20", "--quiet"},
                               dir + "/suggest.log", &output),
            0)
      << output;
  std::smatch t_ref, t_meas, bias;
  ASSERT_TRUE(std::regex_search(output, t_ref, std::regex(R"(t_ref_ms: ([0-9.]+))"))) << output;
  ASSERT_TRUE(std::regex_search(output, t_meas, std::regex(R"(t_meas_ms: \[([0-9., ]+)\])")))
      << output;
  ASSERT_TRUE(std::regex_search(output, bias, std::regex(R"(bias_ma: ([0-9.]+))"))) << output;
  const double t_ref_ms = std::stod(t_ref[1]);
  const std::vector<double> t_meas_ms = ParseList(t_meas[1]);
  ASSERT_EQ(t_meas_ms.size(), 4u);
  EXPECT_GT(t_meas_ms.front(), t_ref_ms);
  // The probe run is recorded like any run (and checks clean).
  EXPECT_TRUE(std::filesystem::exists(dir + "/run/recording/frames.csv"));

  const sim::RigPhysics physics =
      sim::LoadRigPhysics(std::string(IRDIST_SOURCE_DIR) + "/recipes/rigs/virtual.yaml");
  const sim::Renderer renderer(physics);
  const double full_scale = 4095.0;  // the rig's Mono12
  // The smoke recipe's brightest pose (1500 mm, 0 deg, 500 mA) at the longest t_n.
  sim::PoseState nearest;
  nearest.slide_mm = 1500.0;
  nearest.bias_ma = 500.0;
  const sim::GroundTruth bright =
      renderer.Describe(nearest, t_meas_ms.back() * 1e-3, sim::PixelFormat::kMono12);
  EXPECT_FALSE(bright.saturated);
  EXPECT_LT(bright.peak_gray, 0.9 * full_scale) << bright.BriefReport();
  EXPECT_GT(bright.peak_gray, 0.5 * full_scale)  // and the dynamic range is used
      << bright.BriefReport();
  // Its faintest (2500 mm, 30 deg, 475 mA) at t_r still rises well above the background.
  sim::PoseState farthest;
  farthest.slide_mm = 2500.0;
  farthest.pan_deg = 30.0;
  farthest.bias_ma = 475.0;
  const sim::GroundTruth faint =
      renderer.Describe(farthest, t_ref_ms * 1e-3, sim::PixelFormat::kMono12);
  const sim::GroundTruth dark = renderer.Describe(farthest, 1e-6, sim::PixelFormat::kMono12);
  EXPECT_GT(faint.peak_gray - dark.peak_gray, 0.05 * full_scale) << faint.BriefReport();
}

}  // namespace
}  // namespace irdist
