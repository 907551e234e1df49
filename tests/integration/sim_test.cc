// `irdist sim` prints what to connect to, leaves a state file that `irdist devices` lists, and
// stops cleanly (exit 0, state file removed) on SIGINT.
#include <gtest/gtest.h>
#include <signal.h>

#include <filesystem>
#include <regex>

#include "tests/integration/run_helpers.h"
#include "tests/loopback_gvcp.h"

namespace irdist {
namespace {

TEST(Sim, PrintsCameraAndStationAndStopsOnSigint) {
  const std::string dir = testing::ScratchDir("sim");
  testing::LoopbackGvcpLock lock;
  testing::Child sim({"sim", "--time-scale", "10"}, dir + "/sim.log");
  std::string log;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (sim.Running() && std::chrono::steady_clock::now() < deadline) {
    log = testing::ReadAll(dir + "/sim.log");
    if (log.find("Running until") != std::string::npos) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  std::smatch camera, station, state;
  ASSERT_TRUE(
      std::regex_search(log, camera, std::regex(R"(camera: (\S+) 127\.0\.0\.1 serial (\S+))")))
      << log;
  EXPECT_EQ(camera[2].str(), "IRDV0001");
  ASSERT_TRUE(std::regex_search(log, station, std::regex(R"(station: (/dev/\S+))"))) << log;
  EXPECT_TRUE(std::filesystem::exists(station[1].str())) << station[1];
  ASSERT_TRUE(std::regex_search(log, state, std::regex(R"(state: (\S+\.yaml))"))) << log;
  EXPECT_TRUE(std::filesystem::exists(state[1].str()));

  std::string devices;
  EXPECT_EQ(testing::RunIrdist({"devices"}, dir + "/devices.log", &devices), 0) << devices;
  EXPECT_NE(devices.find(station[1].str()), std::string::npos) << devices;
  EXPECT_NE(devices.find("not searched"), std::string::npos) << devices;

  sim.Signal(SIGINT);
  EXPECT_EQ(sim.Wait(std::chrono::seconds(30)), 0) << testing::ReadAll(dir + "/sim.log");
  EXPECT_NE(testing::ReadAll(dir + "/sim.log").find("stopped"), std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(state[1].str()));
}

}  // namespace
}  // namespace irdist
