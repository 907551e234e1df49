// The FLIR PTU-E emulator spoken to in raw command lines over its pty, from the PTU command
// reference (no station/ code).

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <thread>

#include "base/input_error.h"
#include "tests/sim/pty_host.h"

namespace irdist::sim {
namespace {

using testing::PtyHost;
using testing::WaitFor;

std::string Rig(const std::string& virtual_extra = "") {
  return "station:\n"
         "  devices:\n"
         "    head:\n"
         "      driver: flir_ptu\n"
         "      port: auto\n"
         "      axes: {pan: pan, tilt: tilt}\n"
         "virtual:\n"
         "  devices:\n"
         "    head:\n"
         "      pan_resolution_arcsec: 90.0\n"
         "      tilt_resolution_arcsec: 45.0\n"
         "      pan_min_pos: -3000\n"
         "      pan_max_pos: 3000\n"
         "      pan_speed_pos_s: 1000\n"
         "      pan_accel_pos_s2: 2000\n"
         "      verbose: false\n" +
         virtual_extra;
}

class PtuEmulatorTest : public ::testing::Test {
 protected:
  void SetUp() override {
    emulator_ = testing::MakeEmulator(world_, "flir_ptu", "head", Rig());
    ASSERT_NE(emulator_, nullptr);
    host_path_ = emulator_->Start();
    host_ = std::make_unique<PtyHost>(host_path_);
  }
  std::string Ask(const std::string& command, int timeout_ms = 5000) {
    return host_->Ask(command + "\r\n", timeout_ms);
  }

  World world_{20.0};
  std::unique_ptr<DeviceEmulator> emulator_;
  std::unique_ptr<PtyHost> host_;
  std::string host_path_;
};

TEST_F(PtuEmulatorTest, AnswersVersionResolutionAndLimits) {
  EXPECT_EQ(Ask("V").substr(0, 2), "* ");
  EXPECT_NE(Ask("V").find("Pan-Tilt Controller"), std::string::npos);
  EXPECT_EQ(Ask("PR"), "* 90");
  EXPECT_EQ(Ask("TR"), "* 45");
  EXPECT_EQ(Ask("PN"), "* -3000");
  EXPECT_EQ(Ask("PX"), "* 3000");
  EXPECT_EQ(Ask("TN"), "* -3600");
  EXPECT_EQ(Ask("TX"), "* 3600");
  EXPECT_EQ(Ask("FV"), "*");
  EXPECT_EQ(Ask("PR"), "* 90 seconds arc per Pan position");
  EXPECT_EQ(Ask("PP"), "* Current Pan position is 0");
}

TEST_F(PtuEmulatorTest, MovesInSimulatedTimeAndAwaitAnswersWhenStopped) {
  const double start_s = world_.clock().Now();
  EXPECT_EQ(Ask("PP2000"), "*");
  EXPECT_EQ(Ask("TP-800"), "*");
  EXPECT_TRUE(world_.Pose().moving);
  EXPECT_EQ(Ask("A", 5000), "*");
  EXPECT_GE(world_.clock().Now() - start_s, 2000.0 / 1000.0);  // at <= 1000 positions/s
  EXPECT_EQ(Ask("PP"), "* 2000");
  EXPECT_EQ(Ask("TP"), "* -800");
  EXPECT_NEAR(world_.Pose().pan_deg, 2000 * 90.0 / 3600.0, 1e-9);
  EXPECT_NEAR(world_.Pose().tilt_deg, -800 * 45.0 / 3600.0, 1e-9);
  EXPECT_FALSE(world_.Pose().moving);
  EXPECT_EQ(Ask("PO-500"), "*");
  EXPECT_EQ(Ask("A", 5000), "*");
  EXPECT_EQ(Ask("PP"), "* 1500");
}

TEST_F(PtuEmulatorTest, KeepsSpeedBoundsAndPowerModes) {
  EXPECT_EQ(Ask("PU"), "* 12000");
  EXPECT_EQ(Ask("PB300"), "*");
  EXPECT_EQ(Ask("PB"), "* 300");
  EXPECT_EQ(Ask("THL"), "*");
  EXPECT_EQ(Ask("TH"), "* L");
  EXPECT_EQ(Ask("PMX"), "! Illegal argument");
  EXPECT_EQ(Ask("LE"), "*");
  EXPECT_EQ(Ask("CI"), "*");
}

TEST_F(PtuEmulatorTest, SeveralCommandsOnOneLineAndSpacedArguments) {
  host_->Send("PS 2000 PS A\r\n");
  EXPECT_EQ(host_->ReadLine(), "*");
  EXPECT_EQ(host_->ReadLine(), "* 2000");
  EXPECT_EQ(host_->ReadLine(), "*");
}

TEST_F(PtuEmulatorTest, RefusesPositionsBeyondTheLimitsAndBadCommands) {
  EXPECT_EQ(Ask("PP3001"), "! Maximum allowable Pan position exceeded");
  EXPECT_EQ(Ask("PP-3001"), "! Minimum allowable Pan position exceeded");
  EXPECT_EQ(Ask("TP4000"), "! Maximum allowable Tilt position exceeded");
  EXPECT_EQ(Ask("PPx"), "! Illegal argument");
  EXPECT_EQ(Ask("QQ"), "! Illegal command");
  EXPECT_EQ(Ask("PS0"), "! Minimum allowable Pan speed exceeded");
  EXPECT_EQ(Ask("PS999999"), "! Maximum allowable Pan speed exceeded");
  EXPECT_EQ(Ask("PP"), "* 0");
}

TEST_F(PtuEmulatorTest, HaltStopsAndResetReturnsHome) {
  EXPECT_EQ(Ask("PP3000"), "*");
  EXPECT_TRUE(WaitFor([this] { return world_.Pose().pan_deg > 5.0; }));
  EXPECT_EQ(Ask("H"), "*");
  // The world sees the halt at the emulator's next motion tick, not with the reply.
  EXPECT_TRUE(WaitFor([this] { return !world_.Pose().moving; }));
  const double halted_deg = world_.Pose().pan_deg;
  EXPECT_LT(halted_deg, 3000 * 90.0 / 3600.0);
  EXPECT_EQ(Ask("R", 5000), "*");
  EXPECT_EQ(Ask("PP"), "* 0");
  EXPECT_NEAR(world_.Pose().pan_deg, 0.0, 1e-9);
}

TEST_F(PtuEmulatorTest, FaultsDropGarbleDelayStickAndPowerCycle) {
  EmulatorFaults faults;
  faults.drop_rate = 1.0;
  emulator_->SetFaults(faults);
  EXPECT_EQ(Ask("PP", 300), "");
  faults = EmulatorFaults();
  faults.garble_rate = 1.0;
  emulator_->SetFaults(faults);
  EXPECT_NE(Ask("PP"), "* 0");
  faults = EmulatorFaults();
  faults.delay_rate = 1.0;
  faults.delay_s = 4.0;
  emulator_->SetFaults(faults);
  const double start_s = world_.clock().Now();
  EXPECT_EQ(Ask("PP"), "* 0");
  EXPECT_GE(world_.clock().Now() - start_s, 4.0);
  faults = EmulatorFaults();
  faults.stuck_axis = "tilt";
  emulator_->SetFaults(faults);
  EXPECT_EQ(Ask("TP1000"), "*");
  EXPECT_EQ(Ask("A", 5000), "*");
  EXPECT_EQ(Ask("TP"), "* 0");
  faults = EmulatorFaults();
  faults.power_cycle_after_s = 0.5;
  emulator_->SetFaults(faults);
  EXPECT_EQ(Ask("FV"), "*");
  EXPECT_EQ(Ask("PP2000"), "*");
  EXPECT_EQ(Ask("A", 5000), "*");  // the power-up reset brings it back to 0
  // The power-up prints the controller's banner and "Initializing..." (the manuals' power-up).
  EXPECT_NE(host_->ReadLine().find("Pan-Tilt Controller"), std::string::npos);
  EXPECT_EQ(host_->ReadLine(), "Initializing...");
  EXPECT_EQ(Ask("PP"), "* 0");      // and the feedback mode is the power-on one (terse)
}

// The manuals' replies end with CR alone (`reply_line_end: cr`).
TEST(PtuEmulatorReplies, EndWithCrAloneWhenConfigured) {
  World world(20.0);
  auto emulator = testing::MakeEmulator(world, "flir_ptu", "head",
                                        Rig("      reply_line_end: cr\n"));
  ASSERT_NE(emulator, nullptr);
  PtyHost host(emulator->Start());
  host.Send("PR\r");
  host.Send("TR\r");
  EXPECT_EQ(host.ReadRaw(500), "* 90\r* 45\r");
  EXPECT_THROW(testing::MakeEmulator(world, "flir_ptu", "head", Rig("      reply_line_end: lf\n")),
               InputError);
}

// A reset takes reset_s: commands sent meanwhile wait and are answered in order once it ends.
TEST(PtuEmulatorReset, CommandsDuringAResetAreAnsweredWhenItEnds) {
  World world(1.0);
  auto emulator = testing::MakeEmulator(world, "flir_ptu", "head",
                                        Rig("      reset_s: 0.5\n"
                                            "      reset_on_power_up: false\n"));
  ASSERT_NE(emulator, nullptr);
  PtyHost host(emulator->Start());
  EXPECT_EQ(host.Ask("PP\r\n"), "* 0");
  const double start_s = world.clock().Now();
  host.Send("R\r\n");
  host.Send("PP\r\n");
  host.Send("TP\r\n");
  EXPECT_EQ(host.ReadLine(100), "");  // resetting: silent
  EXPECT_EQ(host.ReadLine(3000), "*");
  EXPECT_GE(world.clock().Now() - start_s, 0.5);
  EXPECT_EQ(host.ReadLine(1000), "* 0");
  EXPECT_EQ(host.ReadLine(1000), "* 0");
}

// Regression: a unit power-cycled mid-run prints its banner and "Initializing..." as the
// manuals' power-up shows, and with its power-up echo on echoes each command sent during the
// reset at once; the commands are answered, in order, only when the reset ends.
TEST(PtuEmulatorReset, APowerCyclePrintsItsBannerAndEchoesWhileItResets) {
  World world(1.0);
  auto emulator = testing::MakeEmulator(world, "flir_ptu", "head",
                                        Rig("      reset_s: 1.0\n"
                                            "      echo: true\n"));
  ASSERT_NE(emulator, nullptr);
  PtyHost host(emulator->Start());
  std::this_thread::sleep_for(std::chrono::milliseconds(1200));  // the first power-up: unseen
  host.Send("ED\r\n");
  EXPECT_EQ(host.ReadLine(1000), "ED");  // echoed: echo is on at power-up
  EXPECT_EQ(host.ReadLine(1000), "*");
  EXPECT_EQ(host.Ask("PP2000\r\n"), "*");
  EXPECT_EQ(host.Ask("A\r\n", 5000), "*");  // at 2000: the power-up reset's return takes 2 s
  emulator->PowerCycle();
  const double start_s = world.clock().Now();
  EXPECT_EQ(host.ReadLine(1000), "Pan-Tilt Controller v3.4.2 (emulated, irdist)");
  EXPECT_EQ(host.ReadLine(1000), "Initializing...");
  host.Send("PP\r\n");
  host.Send("A\r\n");  // await: run once the reset ends, it waits in simulated time itself
  host.Send("V\r\n");
  EXPECT_EQ(host.ReadLine(300), "PP");  // echoed at once, though the unit is resetting
  EXPECT_EQ(host.ReadLine(300), "A");
  EXPECT_EQ(host.ReadLine(300), "V");
  EXPECT_EQ(host.ReadLine(200), "");    // no answer yet
  EXPECT_EQ(host.ReadLine(3000).substr(0, 2), "* ");  // on its way back to 0
  EXPECT_GE(world.clock().Now() - start_s, 1.0);
  EXPECT_EQ(host.ReadLine(5000), "*");  // A: once the axes stand at 0
  EXPECT_NE(host.ReadLine(1000).find("* Pan-Tilt Controller"), std::string::npos);
  EXPECT_EQ(host.Ask("PP\r\n"), "PP");  // echo on still (the power-up default)
  EXPECT_EQ(host.ReadLine(1000), "* 0");
}

TEST_F(PtuEmulatorTest, AnExclusiveFlagLeftByADeadClientIsCleared) {
  testing::ExpectAbandonedExclusiveReleased(host_path_);
}

TEST_F(PtuEmulatorTest, ASpeedAboveTheUpperBoundIsRefused) {
  EXPECT_EQ(Ask("PU1500"), "*");
  EXPECT_EQ(Ask("PS1600"), "! Maximum allowable Pan speed exceeded");
  EXPECT_EQ(Ask("PS1500"), "*");
  EXPECT_EQ(Ask("PL200"), "*");
  EXPECT_EQ(Ask("PS100"), "! Minimum allowable Pan speed exceeded");
}

// Fault limit_hit_axis: the axis stalls halfway through its next move and the unit says "!P".
TEST(PtuEmulatorFaults, ALimitHitIsReportedUnasked) {
  World world(20.0);
  auto emulator = testing::MakeEmulator(world, "flir_ptu", "head",
                                        Rig("      limit_hit_axis: pan\n"));
  ASSERT_NE(emulator, nullptr);
  PtyHost host(emulator->Start());
  EXPECT_EQ(host.Ask("PP2000\r\n"), "*");
  EXPECT_EQ(host.ReadLine(5000), "!P");
  const std::string pan = host.Ask("PP\r\n");
  const long position = std::strtol(pan.substr(2).c_str(), nullptr, 10);
  EXPECT_GT(position, 0);
  EXPECT_LT(position, 2000);
}

TEST(PtuEmulatorRig, AxesMustNamePanOrTilt) {
  World world(1.0);
  std::string rig = Rig();
  rig.replace(rig.find("tilt: tilt"), 10, "tilt: roll");
  EXPECT_THROW(testing::MakeEmulator(world, "flir_ptu", "head", rig), InputError);
  EXPECT_THROW(testing::MakeEmulator(world, "flir_ptu", "head", Rig("      pan_speed: 3\n")),
               InputError);
}

}  // namespace
}  // namespace irdist::sim
