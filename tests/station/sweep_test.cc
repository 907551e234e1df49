#include "station/sweep.h"

#include <gtest/gtest.h>

#include <fstream>
#include <map>

#include "tests/station/rig_fixture.h"

namespace irdist {
namespace {

using testing::VirtualStationRig;

std::vector<Pose> Grid() {
  std::vector<Pose> poses;
  std::int64_t index = 100;
  for (double slide : {1500.0, 2000.0, 2500.0}) {
    for (double pan : {0.0, 10.0}) poses.push_back({index++, slide, pan, 0.0, 500.0});
  }
  return poses;
}

TEST(SweepOptions, DefaultsAreValid) {
  std::string why;
  EXPECT_TRUE(SweepOptions{}.IsValid(&why)) << why;
  SweepOptions bad;
  bad.max_retakes = -1;
  EXPECT_FALSE(bad.IsValid(&why));
}

TEST(Sweep, VisitsEveryPoseSettledAtItsCurrentThenParksIredOff) {
  VirtualStationRig rig(100.0);
  Sweep sweep(*rig.station);
  std::vector<std::int64_t> seen;
  const std::vector<Pose> poses = Grid();
  const SweepResult r = sweep.Run(poses, [&](const Pose& p, int attempt) {
    const sim::PoseState truth = rig.world.Pose();
    EXPECT_FALSE(truth.moving);
    EXPECT_NEAR(truth.slide_mm, p.slide_mm, 1e-6);
    EXPECT_NEAR(truth.pan_deg, p.pan_deg, 1e-6);
    EXPECT_DOUBLE_EQ(truth.bias_ma, p.bias_ma);
    EXPECT_EQ(attempt, 0);
    seen.push_back(p.index);
  });
  EXPECT_EQ(r.poses_done, poses.size());
  EXPECT_FALSE(r.stopped);
  ASSERT_EQ(seen.size(), poses.size());
  for (std::size_t i = 0; i < poses.size(); ++i) EXPECT_EQ(seen[i], poses[i].index);
  EXPECT_DOUBLE_EQ(rig.world.Pose().bias_ma, 0.0);
  EXPECT_DOUBLE_EQ(rig.world.Pose().pan_deg, 0.0);
  EXPECT_NE(r.BriefReport().find("6 poses done"), std::string::npos);
}

TEST(Sweep, CurrentFirstAndNoMoveWhenOnlyTheCurrentChanges) {
  VirtualStationRig rig(100.0);
  Sweep sweep(*rig.station);
  const std::vector<Pose> poses = {{0, 1800.0, 10.0, 0.0, 450.0},
                                        {1, 1800.0, 10.0, 0.0, 500.0},
                                        {2, 1800.0, 10.0, 0.0, 550.0},
                                        {3, 2000.0, 10.0, 0.0, 450.0}};
  sweep.Run(poses, [&](const Pose& p, int) {
    EXPECT_DOUBLE_EQ(rig.world.Pose().bias_ma, p.bias_ma);
    EXPECT_NEAR(rig.world.Pose().slide_mm, p.slide_mm, 1e-6);
  });
  rig.station.reset();  // closes the link
  rig.log.reset();      // flush
  std::ifstream in(std::string(IRDIST_BINARY_DIR) +
                   "/station_test_CurrentFirstAndNoMoveWhenOnlyTheCurrentChanges.log");
  std::string line;
  int moves = 0;
  bool current_before_second_move = false;
  int currents = 0;
  while (std::getline(in, line)) {
    if (line.find("> #") == std::string::npos) continue;
    if (line.find(" SOUR:CURR ") != std::string::npos) ++currents;
    if (line.find(" MOVE ") != std::string::npos) {
      ++moves;
      if (moves == 2) current_before_second_move = currents == 4;  // 450, 500, 550, 450
    }
  }
  // Homing is not a MOVE; the sweep moves to 1800, then to 2000, then parks.
  EXPECT_EQ(moves, 3);
  EXPECT_TRUE(current_before_second_move);
}

TEST(Sweep, RebootDuringAPoseRetakesIt) {
  VirtualStationRig rig(100.0);
  Sweep sweep(*rig.station);
  std::map<std::int64_t, int> attempts;
  const SweepResult r = sweep.Run(Grid(), [&](const Pose& p, int attempt) {
    attempts[p.index] = std::max(attempts[p.index], attempt);
    EXPECT_DOUBLE_EQ(rig.world.Pose().bias_ma, p.bias_ma);  // restored on the retake too
    EXPECT_NEAR(rig.world.Pose().slide_mm, p.slide_mm, 1e-6);
    if (p.index == 102 && attempt == 0) rig.emulator.Reboot();  // power glitch during capture
  });
  EXPECT_EQ(r.poses_done, 6u);
  EXPECT_EQ(r.retakes, 1u);
  EXPECT_EQ(r.reboots, 1u);
  EXPECT_EQ(attempts[102], 1);
  EXPECT_EQ(attempts[103], 0);
}

TEST(Sweep, RebootMidMoveRetakesThePose) {
  VirtualStationRig rig(100.0);
  Sweep sweep(*rig.station);
  int calls = 0;
  const std::vector<Pose> poses = Grid();
  const SweepResult r = sweep.Run(poses, [&](const Pose& p, int) {
    if (++calls == 2) rig.emulator.RebootDuringNextMove(0.5);
    EXPECT_NEAR(rig.world.Pose().slide_mm, p.slide_mm, 1e-6);
  });
  EXPECT_EQ(r.poses_done, poses.size());
  EXPECT_EQ(r.reboots, 1u);
  EXPECT_EQ(calls, 6);  // the reboot came before the callback: nothing to retake there
  EXPECT_EQ(rig.emulator.Reboots(), 1u);
}

TEST(Sweep, StopFlagFinishesThePoseInFlightAndParks) {
  VirtualStationRig rig(100.0);
  Sweep sweep(*rig.station);
  std::atomic<bool> stop{false};
  int calls = 0;
  const SweepResult r = sweep.Run(
      Grid(),
      [&](const Pose&, int) {
        if (++calls == 3) stop = true;  // Ctrl-C while capturing the third pose
      },
      &stop);
  EXPECT_TRUE(r.stopped);
  EXPECT_EQ(r.poses_done, 3u);
  EXPECT_EQ(r.next_index, 103);
  EXPECT_DOUBLE_EQ(rig.world.Pose().bias_ma, 0.0);
  EXPECT_FALSE(rig.world.Pose().moving);
}

TEST(Sweep, CallbackFailureSwitchesIredOff) {
  VirtualStationRig rig(100.0);
  Sweep sweep(*rig.station);
  EXPECT_THROW(sweep.Run(Grid(), [&](const Pose&, int) { throw Error("camera lost"); }),
               Error);
  EXPECT_DOUBLE_EQ(rig.world.Pose().bias_ma, 0.0);
}

// Each pose is confirmed (every device seen alive after the callback) before anything moves again,
// so what the caller commits there survives whatever happens during the next move.
TEST(Sweep, ConfirmsEachPoseBeforeTheNextMove) {
  VirtualStationRig rig(100.0);
  Sweep sweep(*rig.station);
  std::vector<std::int64_t> confirmed;
  const std::vector<Pose> poses = Grid();
  sweep.Run(
      poses, [&](const Pose&, int) {}, nullptr,
      [&](const Pose& p) {
        const sim::PoseState truth = rig.world.Pose();
        EXPECT_FALSE(truth.moving);
        EXPECT_NEAR(truth.slide_mm, p.slide_mm, 1e-6);
        EXPECT_NEAR(truth.pan_deg, p.pan_deg, 1e-6);
        confirmed.push_back(p.index);
      });
  ASSERT_EQ(confirmed.size(), poses.size());
  for (std::size_t i = 0; i < poses.size(); ++i) EXPECT_EQ(confirmed[i], poses[i].index);
}

// The station refuses the move to the fifth pose (its own soft limit is below the recipe's):
// the four poses before it were confirmed, the error names the refusal, the IRED is off.
TEST(Sweep, ARefusedMoveKeepsThePosesConfirmedBeforeIt) {
  sim::EmulatorOptions options;
  options.slide.max = 2200.0;
  VirtualStationRig rig(100.0, options);
  Sweep sweep(*rig.station);
  std::vector<std::int64_t> confirmed;
  try {
    sweep.Run(Grid(), [](const Pose&, int) {}, nullptr,
              [&](const Pose& p) { confirmed.push_back(p.index); });
    ADD_FAILURE() << "the refused move did not stop the sweep";
  } catch (const DeviceError& e) {
    EXPECT_EQ(e.device_code(), "-222") << e.what();
  }
  EXPECT_EQ(confirmed, (std::vector<std::int64_t>{100, 101, 102, 103}));
  EXPECT_DOUBLE_EQ(rig.world.Pose().bias_ma, 0.0);
}

// The e-stop is pressed while the third pose is captured: the sweep says so at once (before any
// move) and does not confirm that pose.
TEST(Sweep, AnEStopDuringABracketIsReportedBeforeAnyMove) {
  VirtualStationRig rig(100.0);
  Sweep sweep(*rig.station);
  std::vector<std::int64_t> confirmed;
  try {
    sweep.Run(
        Grid(),
        [&](const Pose& p, int) {
          if (p.index == 102) rig.emulator.PressEmergencyStop();
        },
        nullptr, [&](const Pose& p) { confirmed.push_back(p.index); });
    ADD_FAILURE() << "the e-stop did not stop the sweep";
  } catch (const DeviceError& e) {
    EXPECT_NE(std::string(e.what()).find("emergency stop"), std::string::npos) << e.what();
  }
  EXPECT_EQ(confirmed, (std::vector<std::int64_t>{100, 101}));
}

// The station stops answering during the third pose: the two before it stay confirmed.
TEST(Sweep, ASilentStationLosesOnlyThePoseInFlight) {
  VirtualStationRig rig(100.0);
  Sweep sweep(*rig.station);
  std::vector<std::int64_t> confirmed;
  EXPECT_THROW(sweep.Run(
                   Grid(),
                   [&](const Pose& p, int) {
                     if (p.index == 102) rig.emulator.SetDropRate(1.0);
                   },
                   nullptr, [&](const Pose& p) { confirmed.push_back(p.index); }),
               LinkError);
  EXPECT_EQ(confirmed, (std::vector<std::int64_t>{100, 101}));
}

}  // namespace
}  // namespace irdist
