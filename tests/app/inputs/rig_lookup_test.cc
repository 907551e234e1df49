// The rig a `--rig` value names (a path, or a name in recipes/rigs/) and FindRunningSim over the
// state files (app/inputs/state_file.h).
#include "app/inputs/rig_lookup.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "app/inputs/errors.h"
#include "tests/app/fake_sim.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;

class RigLookupTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("irdist-rig-lookup-" + std::to_string(::getpid()) + "-" +
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

TEST_F(RigLookupTest, ResolveRigTakesAPathThatExistsAsGiven) {
  const fs::path rig = dir_ / "rigs" / "mine.yaml";
  std::ofstream(rig) << "kind: virtual\n";
  EXPECT_EQ(ResolveRig(rig.string()), rig.string());
}

// A bare name is a rig file of the shipped recipes/rigs/ (the source tree's in a build).
TEST_F(RigLookupTest, ResolveRigFindsANameInTheShippedRigs) {
  const std::string found = ResolveRig("virtual");
  EXPECT_TRUE(fs::equivalent(found, std::string(IRDIST_SOURCE_DIR) + "/recipes/rigs/virtual.yaml"))
      << found;
}

TEST_F(RigLookupTest, ResolveRigRefusesANameWithNoRigFile) {
  try {
    ResolveRig("no-such-rig");
    FAIL() << "a rig name with no file was resolved";
  } catch (const RecipeError& e) {
    EXPECT_NE(std::string(e.what()).find("no such rig"), std::string::npos) << e.what();
  }
}

// measure, snap, view and station find a running sim of the same rig file (the same file by
// another path too); a sim of another rig file and the stale file of a dead one are skipped.
TEST_F(RigLookupTest, FindRunningSimMatchesTheRigFileAndALiveSim) {
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
TEST_F(RigLookupTest, FindRunningSimIgnoresAPlantedStateFile) {
  const fs::path rig = dir_ / "rigs" / "mine.yaml";
  std::ofstream(rig) << "kind: virtual\n";
  Plant("1", "pid: 1\nrig: \"" + rig.string() + "\"\nstation_port: \"/dev/pts/0\"\n");
  std::ostringstream warn;
  EXPECT_FALSE(FindRunningSim(rig.string(), warn).has_value());
  EXPECT_NE(warn.str().find("irdist-sim-1.yaml"), std::string::npos) << warn.str();
}

}  // namespace
}  // namespace irdist
