// `irdist devices` without --discover (never broadcasts) and the state-file folder. `irdist sim`
// itself runs in tests/integration/sim_test.cc.
#include "app/tools.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace irdist {
namespace {

namespace fs = std::filesystem;

TEST(ToolsTest, StateFilesGoToXdgRuntimeDirOrTmp) {
  const fs::path dir = fs::temp_directory_path() / ("irdist-tools-" + std::to_string(getpid()));
  fs::create_directories(dir);
  setenv("XDG_RUNTIME_DIR", dir.c_str(), 1);
  EXPECT_EQ(SimStateDir(), dir.string());
  setenv("XDG_RUNTIME_DIR", (dir / "missing").c_str(), 1);
  EXPECT_EQ(SimStateDir(), "/tmp");
  unsetenv("XDG_RUNTIME_DIR");
  EXPECT_EQ(SimStateDir(), "/tmp");
  fs::remove_all(dir);
}

TEST(ToolsTest, DevicesListsLiveRigsAndSkipsStaleStateFiles) {
  const fs::path dir = fs::temp_directory_path() / ("irdist-devices-" + std::to_string(getpid()));
  fs::create_directories(dir);
  setenv("XDG_RUNTIME_DIR", dir.c_str(), 1);
  {
    std::ofstream live(dir / ("irdist-sim-" + std::to_string(getpid()) + ".yaml"));
    live << "pid: " << getpid() << "\ncamera_id: \"Aravis-Fake-LIVE\"\ncamera_address: "
         << "\"127.0.0.1\"\nserial: \"LIVE\"\nstation_port: \"/dev/pts/live\"\ntime_scale: 5\n";
    std::ofstream stale(dir / "irdist-sim-999999999.yaml");
    stale << "pid: 999999999\ncamera_id: \"Aravis-Fake-STALE\"\ncamera_address: \"127.0.0.1\"\n"
          << "serial: \"STALE\"\nstation_port: \"/dev/pts/stale\"\ntime_scale: 1\n";
  }
  std::ostringstream out, err;
  RunDevices(DevicesArgs{}, {out, err});
  const std::string text = out.str();
  EXPECT_NE(text.find("/dev/pts/live"), std::string::npos) << text;
  EXPECT_EQ(text.find("STALE"), std::string::npos) << text;
  EXPECT_NE(text.find("Serial ports:"), std::string::npos) << text;
  EXPECT_NE(text.find("not searched"), std::string::npos) << text;
  unsetenv("XDG_RUNTIME_DIR");
  fs::remove_all(dir);
}

// measure, snap, view and station find a running sim of the same rig file (the same file by
// another path too); a sim of another rig file and the stale file of a dead one are skipped.
TEST(ToolsTest, FindRunningSimMatchesTheRigFileAndALiveProcess) {
  const fs::path dir = fs::temp_directory_path() / ("irdist-find-sim-" + std::to_string(getpid()));
  fs::create_directories(dir / "rigs");
  setenv("XDG_RUNTIME_DIR", dir.c_str(), 1);
  const fs::path rig = dir / "rigs" / "mine.yaml";
  std::ofstream(rig) << "kind: virtual\n";
  std::ofstream(dir / "rigs" / "other.yaml") << "kind: virtual\n";
  EXPECT_FALSE(FindRunningSim(rig.string()).has_value());
  {
    std::ofstream stale(dir / "irdist-sim-999999999.yaml");
    stale << "pid: 999999999\nrig: \"" << rig.string() << "\"\nserial: \"STALE\"\n";
    std::ofstream other(dir / "irdist-sim-1.yaml");  // pid 1 is alive: only the rig differs
    other << "pid: 1\nrig: \"" << (dir / "rigs" / "other.yaml").string() << "\"\n";
  }
  EXPECT_FALSE(FindRunningSim(rig.string()).has_value());
  {
    std::ofstream live(dir / ("irdist-sim-" + std::to_string(getpid()) + ".yaml"));
    live << "pid: " << getpid() << "\nrig: \"" << rig.string() << "\"\ncamera_address: "
         << "\"127.0.0.1\"\nserial: \"LIVE\"\ntime_scale: 10\n";
  }
  const auto sim = FindRunningSim((dir / "rigs" / ".." / "rigs" / "mine.yaml").string());
  ASSERT_TRUE(sim.has_value());
  EXPECT_EQ(sim->pid, static_cast<long>(getpid()));
  EXPECT_EQ(sim->values.at("serial"), "LIVE");
  EXPECT_EQ(sim->values.at("time_scale"), "10");
  const auto other = FindRunningSim((dir / "rigs" / "other.yaml").string());
  ASSERT_TRUE(other.has_value());
  EXPECT_EQ(other->pid, 1L);
  unsetenv("XDG_RUNTIME_DIR");
  fs::remove_all(dir);
}

}  // namespace
}  // namespace irdist
