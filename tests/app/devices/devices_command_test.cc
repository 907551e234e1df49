// `irdist devices` without --discover (never broadcasts): the running sims of the state files
// (app/inputs/state_file.h), stale and planted ones skipped, and the serial ports.
#include "app/devices/devices_command.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "app/inputs/state_file.h"
#include "tests/app/fake_sim.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;

class DevicesCommandTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("irdist-devices-" + std::to_string(::getpid()) + "-" +
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
TEST_F(DevicesCommandTest, DevicesListsLiveRigsAndSkipsStaleAndPlantedStateFiles) {
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
TEST_F(DevicesCommandTest, DevicesListsASimWithMissingKeysWithoutFailing) {
  testing::FakeSim sim(dir_ / "sim");
  Plant(std::to_string(sim.pid()), "pid: " + std::to_string(sim.pid()) + "\n");
  std::ostringstream out, err;
  RunDevices(DevicesArgs{}, {out, err});
  EXPECT_NE(out.str().find("pid " + std::to_string(sim.pid()) + ": camera ?"), std::string::npos)
      << out.str() << err.str();
}

}  // namespace
}  // namespace irdist
