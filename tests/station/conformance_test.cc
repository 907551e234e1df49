#include "station/conformance.h"

#include <gtest/gtest.h>

#include <chrono>
#include <string>

#include "sim/station_emulator.h"
#include "sim/world.h"
#include "station/serial_transport.h"

namespace irdist {
namespace {

ConformanceReport RunAgainst(const sim::EmulatorOptions& options) {
  sim::World world(100.0);
  sim::StationEmulator emulator(world, options);
  SerialTransport transport(emulator.Start());
  ConformanceOptions conformance;
  conformance.reply_timeout = std::chrono::milliseconds(150);
  conformance.poll_period = std::chrono::milliseconds(2);
  return RunConformance(transport, conformance);
}

const ConformanceCheck* Find(const ConformanceReport& report, const std::string& name) {
  for (const ConformanceCheck& c : report.checks) {
    if (c.name == name) return &c;
  }
  return nullptr;
}

TEST(Conformance, TheEmulatorPassesEveryCheck) {
  const ConformanceReport report = RunAgainst({});
  EXPECT_TRUE(report.Passed()) << report.Table();
  EXPECT_GE(report.checks.size(), 14u);
  EXPECT_NE(report.Table().find("checks passed"), std::string::npos);
}

TEST(Conformance, AStationThatRefusesCurrentOffInEStopFails) {
  sim::EmulatorOptions broken;
  broken.refuse_current_off_in_estop = true;
  const ConformanceReport report = RunAgainst(broken);
  EXPECT_FALSE(report.Passed()) << report.Table();
  const ConformanceCheck* check = Find(report, "estop-current-off");
  ASSERT_NE(check, nullptr);
  EXPECT_FALSE(check->passed);
  EXPECT_NE(report.Table().find("FAIL  estop-current-off"), std::string::npos) << report.Table();
}

TEST(Conformance, AnOpenIredFailsTheCurrentCheck) {
  sim::EmulatorOptions open;
  open.open_circuit = true;
  const ConformanceReport report = RunAgainst(open);
  const ConformanceCheck* check = Find(report, "current");
  ASSERT_NE(check, nullptr);
  EXPECT_FALSE(check->passed) << report.Table();
}

// The options refuse a bad field with its name (RunConformance checks them first).
TEST(ConformanceOptions, RefusesEachBadFieldByName) {
  std::string why;
  EXPECT_TRUE(ConformanceOptions().IsValid(&why)) << why;
  ConformanceOptions reply;
  reply.reply_timeout = std::chrono::milliseconds(0);
  EXPECT_FALSE(reply.IsValid(&why));
  EXPECT_EQ(why.rfind("reply_timeout", 0), 0u) << why;
  ConformanceOptions move;
  move.move_timeout = std::chrono::milliseconds(-1);
  EXPECT_FALSE(move.IsValid(&why));
  EXPECT_EQ(why.rfind("move_timeout", 0), 0u) << why;
  ConformanceOptions poll;
  poll.poll_period = std::chrono::milliseconds(-5);
  EXPECT_FALSE(poll.IsValid(&why));
  EXPECT_EQ(why.rfind("poll_period", 0), 0u) << why;
}

}  // namespace
}  // namespace irdist
