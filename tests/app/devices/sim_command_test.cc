// `irdist sim` in process (GIGE: the virtual rig's camera on 127.0.0.1): the rig runs with its
// state file and trajectory log until stopped, then leaves neither behind; a hardware rig or a
// rig name with no file is refused before anything starts. The binary's own run (Ctrl-C, exit
// code) is tests/integration/sim_test.cc's.
#include "app/devices/sim_command.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>
#include <thread>

#include "app/inputs/state_file.h"
#include "app/inputs/stop_signal.h"
#include "tests/loopback_gvcp.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;

class SimCommandTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("irdist-sim-command-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    ASSERT_EQ(setenv("XDG_RUNTIME_DIR", dir_.c_str(), 1), 0);
  }
  void TearDown() override {
    unsetenv("XDG_RUNTIME_DIR");
    fs::remove_all(dir_);
  }
  // This process's state file and trajectory log, as RunSim names them.
  fs::path StateFile() const {
    return fs::path(RuntimeStateDir()) / ("irdist-sim-" + std::to_string(::getpid()) + ".yaml");
  }
  fs::path TrajectoryFile() const {
    return fs::path(RuntimeStateDir()) /
           ("irdist-sim-" + std::to_string(::getpid()) + "-trajectory.csv");
  }
  fs::path dir_;
};

std::string ShippedRig(const std::string& name) {
  return std::string(IRDIST_SOURCE_DIR) + "/recipes/rigs/" + name + ".yaml";
}

TEST_F(SimCommandTest, RunsTheVirtualRigUntilStoppedAndLeavesNoFileBehind) {
  testing::LoopbackGvcpLock lock;
  SimArgs args;
  args.rig = ShippedRig("virtual");
  args.time_scale = 50.0;
  std::ostringstream out, err;
  std::string failure;
  std::thread sim([&] {
    try {
      RunSim(args, {out, err});
    } catch (const std::exception& e) {
      failure = e.what();
    }
  });
  // The state file is written once the rig runs; then Ctrl-C's flag stops it.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  bool running = false;
  while (!running && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    running = fs::exists(StateFile()) && fs::exists(TrajectoryFile());
  }
  StopRequested().store(true);
  sim.join();
  ASSERT_TRUE(running) << "no state file and trajectory log while the sim ran: " << failure;
  ASSERT_EQ(failure, "");
  const std::string text = out.str();
  for (const char* line : {"camera: ", "station: /dev/pts/", "time scale: 50",
                           "trajectory: " , "virtual rig stopped"}) {
    EXPECT_NE(text.find(line), std::string::npos) << line << "\n" << text;
  }
  EXPECT_NE(text.find("state: " + StateFile().string()), std::string::npos) << text;
  EXPECT_FALSE(fs::exists(StateFile()));
  EXPECT_FALSE(fs::exists(TrajectoryFile()));
}

// `irdist sim` runs virtual rigs only: a hardware rig is refused before anything starts.
TEST_F(SimCommandTest, RefusesAHardwareRigBeforeStartingAnything) {
  SimArgs args;
  args.rig = ShippedRig("example-hardware");
  std::ostringstream out, err;
  try {
    RunSim(args, {out, err});
    FAIL() << "a hardware rig was run as a sim";
  } catch (const RecipeError& e) {
    EXPECT_NE(std::string(e.what()).find("rigs of kind virtual only"), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(out.str(), "");
  EXPECT_FALSE(fs::exists(StateFile()));
}

TEST_F(SimCommandTest, RefusesARigNameWithNoRigFile) {
  SimArgs args;
  args.rig = "no-such-rig";
  std::ostringstream out, err;
  EXPECT_THROW(RunSim(args, {out, err}), RecipeError);
  EXPECT_EQ(out.str(), "");
}

}  // namespace
}  // namespace irdist
