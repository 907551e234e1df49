// A station reboot in the middle of a sweep (the emulator's reboot_after_s fault): the sweep
// re-homes, restores the current and retakes the pose; the recording holds every frame once.
#include <gtest/gtest.h>

#include <map>
#include <regex>

#include "acquisition/recording_check.h"
#include "acquisition/recording_reader.h"
#include "tests/integration/run_helpers.h"
#include "tests/loopback_gvcp.h"

namespace irdist {
namespace {

TEST(Reboot, ARebootedStationIsRecoveredWithoutDuplicateFrames) {
  const std::string dir = testing::ScratchDir("reboot");
  std::string rig = testing::ReadAll(std::string(IRDIST_SOURCE_DIR) + "/recipes/rigs/virtual.yaml");
  const std::string key = "reboot_after_s: -1.0";
  ASSERT_NE(rig.find(key), std::string::npos) << "the rig file changed; update this test";
  rig.replace(rig.find(key), key.size(), "reboot_after_s: 20.0");
  testing::WriteAll(dir + "/reboot-rig.yaml", rig);
  testing::WriteAll(dir + "/recipe.yaml", R"(name: it-reboot
rig: reboot-rig.yaml
after: none
axes:
  slide_mm: [1500, 2000, 2500]
  theta_deg: [0, 20]
  bias_ma: [500]
bracket:
  t_ref_ms: 8
  t_meas_ms: [30, 36]
)");
  testing::LoopbackGvcpLock lock;
  std::string output;
  ASSERT_EQ(testing::RunIrdist({"calibrate", dir + "/recipe.yaml", "--out", dir + "/run",
                                "--time-scale", "50", "--quiet"},
                               dir + "/run.log", &output),
            0)
      << output;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(output, m, std::regex(R"((\d+) station reboots)"))) << output;
  EXPECT_EQ(m[1].str(), "1") << output;

  const RecordingReader reader(dir + "/run/recording");
  EXPECT_TRUE(reader.IsComplete());
  EXPECT_EQ(reader.rows().size(), 6u * 3u) << output;
  std::map<std::pair<std::int64_t, int>, int> seen;
  for (const FrameRecord& row : reader.rows()) ++seen[{row.bracket_id, row.frame_in_bracket}];
  EXPECT_EQ(seen.size(), 18u);
  for (const auto& [position, count] : seen) {
    EXPECT_EQ(count, 1) << "bracket " << position.first << " frame " << position.second;
  }
  EXPECT_TRUE(CheckRecording(dir + "/run/recording").ok());
}

}  // namespace
}  // namespace irdist
