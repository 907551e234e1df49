// A track recipe (`kind: track`, docs/recipes.md "Track recipes") through the built binary: a
// small calibration on a virtual rig whose slide accelerates at 2 m/s^2 (recipes/rigs/virtual.yaml
// with the station emulator's slide accel 2000 mm/s^2; its cruise speed stays the rig's 200 mm/s
// until the run sets it), then `irdist validate TRACK_RECIPE` against the running `irdist sim`
// (time scale 1): the slide goes 1500 -> 3000 mm at pan 0 and back at pan 20 deg, each at the
// recipe's 0.5 m/s sent to the station as its SPEED command, while every frame is tracked. The
// run folder's summary.yaml must show the emulator cruising at the recipe's speed (the truth's
// velocity on each cruise: +-500 mm/s, not the rig's 200), the per-frame error's rms during the
// moves at most 1.5 x the one-frame Cramer-Rao bound, the filter's velocity on each cruise within
// 3 standard errors of the truth, no frame lost; track.csv holds a row for every frame. Ctrl-C
// keeps what was taken (a summary marked cut, exit 130); --resume is refused; a bad track recipe
// is refused with its line.
#include <gtest/gtest.h>
#include <signal.h>
#include <stdlib.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <string>
#include <thread>

#include "tests/integration/measure_helpers.h"
#include "tests/integration/run_helpers.h"
#include "tests/loopback_gvcp.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;
using testing::ReadAll;
using testing::RunIrdist;
using testing::WriteAll;

// The recipe: the slide 1500 -> 3000 mm at 0.5 m/s at pan 0, then back 3000 -> 1500 mm at
// 0.5 m/s at pan 20 deg (the pan turned there first, at the station's own speed); 490 mA.
constexpr char kTrackRecipe[] = R"(kind: track
name: track-slide-test
rig: virtual-fast
track:
  bias_ma: 490
  exposure_ms: 8
  settle_ms: 500
  after_ms: 300
  segments:
    - {slide_mm: [1500, 3000], speed_mm_s: 500}
    - {slide_mm: [3000, 1500], speed_mm_s: 500, pan_deg: 20}
)";

// The rows of a track.csv (its header left out).
int CsvRows(const std::string& path) { return std::max(0, testing::CountLines(path) - 1); }

// The finished run's summary.yaml and track.csv: the emulator cruising at the recipe's speed (the
// truth's velocity on each cruise: +-500 mm/s, not the rig's 200), the per-frame error's rms during
// the moves at most 1.5 x the one-frame Cramer-Rao bound, the filter's velocity on each cruise
// within 3 standard errors of the truth, no frame lost, a row in track.csv for every frame.
void ExpectEveryFrameScored(const std::string& run) {
  const YAML::Node s = YAML::LoadFile(run + "/summary.yaml");
  EXPECT_EQ(s["kind"].as<std::string>(), "track");
  EXPECT_FALSE(s["cut"].as<bool>());
  EXPECT_EQ(s["frames"]["lost"].as<int>(), 0) << ReadAll(run + "/summary.yaml");
  EXPECT_EQ(s["frames"]["wrong_exposure"].as<int>(), 0);
  EXPECT_GE(s["frames"]["moving"].as<int>(), 100);  // two moves of about 3.2 s at ~50 frames/s
  const YAML::Node e = s["distance_error_moving"];
  EXPECT_LE(e["rms_mm"].as<double>(), 1.5 * e["one_frame_bound_rms_mm"].as<double>())
      << ReadAll(run + "/summary.yaml");
  EXPECT_TRUE(e["within_goal"].as<bool>());
  const YAML::Node cruises = s["velocity"]["velocity_on_cruise"];
  ASSERT_EQ(cruises.size(), 2u) << ReadAll(run + "/summary.yaml");
  for (std::size_t i = 0; i < cruises.size(); ++i) {
    SCOPED_TRACE("segment " + std::to_string(i));
    EXPECT_EQ(cruises[i]["segment"].as<int>(), static_cast<int>(i));
    // The station cruised at the recipe's speed (the rig's own is 200 mm/s).
    EXPECT_NEAR(cruises[i]["truth_v_mm_per_s"].as<double>(), i == 0 ? 500.0 : -500.0, 1e-6);
    EXPECT_GE(cruises[i]["frames"].as<int>(), 30);
    // The app's within_3se (z_mean <= 3 and z_last <= 3) with the last frame's bound at 4.5, as
    // that one draw per segment would fail 3 se in 0.5% of runs by chance over the two segments.
    EXPECT_LE(cruises[i]["z_mean"].as<double>(NAN), 3.0) << ReadAll(run + "/summary.yaml");
    EXPECT_LE(cruises[i]["z_last"].as<double>(NAN), 4.5) << ReadAll(run + "/summary.yaml");
  }
  // track.csv: its header and one row per frame the summary counted.
  EXPECT_EQ(CsvRows(run + "/track.csv"), s["frames"]["rows"].as<int>());
  EXPECT_EQ(
      ReadAll(run + "/track.csv").rfind("frame,camera_frame_id,camera_timestamp_ns,utc_time", 0),
      0u);
}

class TrackRecipe : public ::testing::Test {
 protected:
  void SetUp() override {
    // One folder per test: the logs of one survive the next.
    dir_ = testing::ScratchDir(
        std::string("track-recipe-") +
        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    // The slide accelerating at 2 m/s^2, its speed left at the rig's 200 mm/s.
    rig_ = testing::FastSlideScratch(dir_, "speed: 200.0, accel: 2000.0");
    ASSERT_FALSE(rig_.empty()) << "recipes/rigs/virtual.yaml's slide changed; update this test";
  }

  int Run(const std::string& name, const std::vector<std::string>& args, std::string* output) {
    return RunIrdist(args, dir_ + "/" + name + ".log", output, std::chrono::seconds(240));
  }

  // Ctrl-C during the first move: the station stops, what was taken is kept (its summary cut),
  // exit 130.
  void ExpectCtrlCKeepsWhatWasTaken() {
    const std::string cut = dir_ + "/cut";
    testing::Child child(
        {"validate", dir_ + "/track.yaml", "--model", dir_ + "/cal/model.yaml", "--out", cut},
        dir_ + "/cut.log");
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
    while (child.Running() && CsvRows(cut + "/track.csv") < 60 &&
           std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    child.Signal(SIGINT);
    EXPECT_EQ(child.Wait(std::chrono::seconds(60)), 130) << ReadAll(dir_ + "/cut.log");
    const YAML::Node c = YAML::LoadFile(cut + "/summary.yaml");
    EXPECT_TRUE(c["cut"].as<bool>());
    EXPECT_GE(c["frames"]["rows"].as<int>(), 60);
    EXPECT_EQ(CsvRows(cut + "/track.csv"), c["frames"]["rows"].as<int>());
    EXPECT_NE(ReadAll(dir_ + "/cut.log").find("not resumable"), std::string::npos);
  }

  std::string dir_, rig_;
};

TEST_F(TrackRecipe, MovesTheSlideAtTheRecipesSpeedAndScoresEveryFrameAgainstTheTruth) {
  WriteAll(dir_ + "/track.yaml", kTrackRecipe);
  std::string output;
  {
    testing::LoopbackGvcpLock lock;
    ASSERT_EQ(Run("calibrate",
                  {"calibrate", dir_ + "/calibration.yaml", "--out", dir_ + "/cal",
                   "--time-scale", "50", "--quiet"},
                  &output),
              0)
        << output;
  }
  testing::LoopbackGvcpLock lock;
  // Without the running sim the run is refused, naming the command that starts it.
  EXPECT_NE(Run("no-sim", {"validate", dir_ + "/track.yaml", "--model", dir_ + "/cal/model.yaml",
                           "--out", dir_ + "/no-sim"},
                &output),
            0);
  EXPECT_NE(output.find("irdist sim"), std::string::npos) << output;
  const std::string sim_log = dir_ + "/sim.log";
  testing::Child sim({"sim", rig_, "--time-scale", "1"}, sim_log);
  ASSERT_FALSE(testing::WaitForSim(sim, sim_log).empty()) << ReadAll(sim_log);

  const std::string run = dir_ + "/track";
  ASSERT_EQ(Run("track", {"validate", dir_ + "/track.yaml", "--model", dir_ + "/cal/model.yaml",
                          "--out", run},
                &output),
            0)
      << output;
  std::cout << output;
  ASSERT_NO_FATAL_FAILURE(ExpectEveryFrameScored(run));
  // The run folder cannot be resumed: refused, saying so.
  EXPECT_NE(Run("resume", {"validate", dir_ + "/track.yaml", "--model", dir_ + "/cal/model.yaml",
                           "--resume", run},
                &output),
            0);
  EXPECT_NE(output.find("not resumable"), std::string::npos) << output;

  ExpectCtrlCKeepsWhatWasTaken();

  ASSERT_EQ(Run("off", {"station", "--rig", rig_, "off"}, &output), 0) << output;
  sim.Signal(SIGINT);
  const int code = sim.Wait(std::chrono::seconds(30));
  EXPECT_TRUE(code == 0 || code == 130) << "exit " << code << "\n" << ReadAll(sim_log);
}

TEST_F(TrackRecipe, ABadTrackRecipeIsRefusedWithItsLine) {
  // Line 7: a segment without its speed; line 8: a pan move without the pan's speed.
  WriteAll(dir_ + "/bad.yaml", R"(kind: track
rig: virtual-fast
track:
  bias_ma: 490
  segments:
    - {slide_mm: [1500, 3000], speed_mm_s: 500}
    - {slide_mm: [3000, 1500], speed_mm_s: -5}
)");
  std::string output;
  EXPECT_NE(Run("bad", {"validate", dir_ + "/bad.yaml", "--model", dir_ + "/none.yaml"}, &output),
            0);
  EXPECT_NE(output.find("bad.yaml:7:"), std::string::npos) << output;
  EXPECT_NE(output.find("speed_mm_s"), std::string::npos) << output;

  WriteAll(dir_ + "/far.yaml", R"(kind: track
rig: virtual-fast
track:
  bias_ma: 490
  segments:
    - {slide_mm: [1500, 9000], speed_mm_s: 500}
)");
  EXPECT_NE(Run("far", {"validate", dir_ + "/far.yaml", "--model", dir_ + "/none.yaml"}, &output),
            0);
  EXPECT_NE(output.find("far.yaml:6:"), std::string::npos) << output;
  EXPECT_NE(output.find("station.limits"), std::string::npos) << output;
  // A track recipe is no sweep: calibrate refuses it, naming the command that runs it.
  EXPECT_NE(Run("calibrate-track", {"calibrate", dir_ + "/far.yaml"}, &output), 0);
  EXPECT_NE(output.find("irdist validate"), std::string::npos) << output;
}

}  // namespace
}  // namespace irdist
