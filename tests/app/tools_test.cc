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

}  // namespace
}  // namespace irdist
