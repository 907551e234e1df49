// `irdist devices` without --discover (never broadcasts) and FindRunningSim over the state files
// (app/inputs/state_file.h). `irdist sim` itself runs in tests/integration/sim_test.cc.
#include "app/devices/tools.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "tests/app/fake_sim.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;

class ToolsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("irdist-tools-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "rigs");
    ASSERT_EQ(setenv("XDG_RUNTIME_DIR", dir_.c_str(), 1), 0);
  }
  void TearDown() override {
    unsetenv("XDG_RUNTIME_DIR");
    fs::remove_all(dir_);
  }
  void Plant(const std::string& name, const std::string& text) {
    std::ofstream(fs::path(RuntimeStateDir()) / ("irdist-sim-" + name + ".yaml")) << text;
  }
  fs::path dir_;
};

// A live sim is listed; a stale file is skipped; a planted file with missing keys or of a
// process that is no irdist sim is warned about, never a map::at.
TEST_F(ToolsTest, DevicesListsLiveRigsAndSkipsStaleAndPlantedStateFiles) {
  testing::FakeSim sim(dir_ / "sim");
  SimState state;
  state.pid = sim.pid();
  state.camera_id = "Aravis-Fake-LIVE";
  state.camera_address = "127.0.0.1";
  state.serial = "LIVE";
  state.station_port = sim.pty();
  state.time_scale = 5;
  WriteSimState(state);
  Plant("999999999", "pid: 999999999\ncamera_id: \"Aravis-Fake-STALE\"\nserial: \"STALE\"\n");
  Plant("1", "pid: 1\n");  // the map::at: keys missing, a process that is no sim
  Plant(std::to_string(::getpid()), "pid: " + std::to_string(::getpid()) + "\n");
  std::ostringstream out, err;
  RunDevices(DevicesArgs{}, {out, err});
  const std::string text = out.str();
  EXPECT_NE(text.find(sim.pty()), std::string::npos) << text;
  EXPECT_NE(text.find("Aravis-Fake-LIVE"), std::string::npos) << text;
  EXPECT_EQ(text.find("STALE"), std::string::npos) << text;
  EXPECT_NE(text.find("Serial ports:"), std::string::npos) << text;
  EXPECT_NE(text.find("not searched"), std::string::npos) << text;
  EXPECT_NE(err.str().find("irdist-sim-1.yaml"), std::string::npos) << err.str();
  EXPECT_EQ(err.str().find("999999999"), std::string::npos) << err.str();
}

// A sim state file with only a pid (a sim of an older irdist, or a hand-made one): listed with
// '?' for what it lacks.
TEST_F(ToolsTest, DevicesListsASimWithMissingKeysWithoutFailing) {
  testing::FakeSim sim(dir_ / "sim");
  Plant(std::to_string(sim.pid()), "pid: " + std::to_string(sim.pid()) + "\n");
  std::ostringstream out, err;
  RunDevices(DevicesArgs{}, {out, err});
  EXPECT_NE(out.str().find("pid " + std::to_string(sim.pid()) + ": camera ?"), std::string::npos)
      << out.str() << err.str();
}

// measure, snap, view and station find a running sim of the same rig file (the same file by
// another path too); a sim of another rig file and the stale file of a dead one are skipped.
TEST_F(ToolsTest, FindRunningSimMatchesTheRigFileAndALiveSim) {
  const fs::path rig = dir_ / "rigs" / "mine.yaml";
  std::ofstream(rig) << "kind: virtual\n";
  std::ofstream(dir_ / "rigs" / "other.yaml") << "kind: virtual\n";
  std::ostringstream warn;
  EXPECT_FALSE(FindRunningSim(rig.string(), warn).has_value());
  testing::FakeSim mine(dir_ / "sim-mine");
  testing::FakeSim other(dir_ / "sim-other");
  Plant("999999999", "pid: 999999999\nrig: \"" + rig.string() + "\"\nserial: \"STALE\"\n");
  SimState state;
  state.pid = other.pid();
  state.rig = (dir_ / "rigs" / "other.yaml").string();
  WriteSimState(state);
  EXPECT_FALSE(FindRunningSim(rig.string(), warn).has_value());
  state.pid = mine.pid();
  state.rig = rig.string();
  state.serial = "LIVE";
  state.time_scale = 10;
  WriteSimState(state);
  const auto sim = FindRunningSim((dir_ / "rigs" / ".." / "rigs" / "mine.yaml").string(), warn);
  ASSERT_TRUE(sim.has_value()) << warn.str();
  EXPECT_EQ(sim->pid, mine.pid());
  EXPECT_EQ(sim->values.at("serial"), "LIVE");
  EXPECT_EQ(sim->values.at("time_scale"), "10");
  const auto found_other = FindRunningSim((dir_ / "rigs" / "other.yaml").string(), warn);
  ASSERT_TRUE(found_other.has_value());
  EXPECT_EQ(found_other->pid, other.pid());
  EXPECT_EQ(warn.str(), "");
}

// The attack on station: a state file of pid 1 naming another pty for the rig is
// ignored (with a warning), so its ports are never opened.
TEST_F(ToolsTest, FindRunningSimIgnoresAPlantedStateFile) {
  const fs::path rig = dir_ / "rigs" / "mine.yaml";
  std::ofstream(rig) << "kind: virtual\n";
  Plant("1", "pid: 1\nrig: \"" + rig.string() + "\"\nstation_port: \"/dev/pts/0\"\n");
  std::ostringstream warn;
  EXPECT_FALSE(FindRunningSim(rig.string(), warn).has_value());
  EXPECT_NE(warn.str().find("irdist-sim-1.yaml"), std::string::npos) << warn.str();
}

}  // namespace
}  // namespace irdist
