// The Zaber ASCII emulator spoken to in raw lines over its pty, from the ASCII protocol manual's
// message format (no station/ code).

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "base/input_error.h"
#include "tests/sim/pty_host.h"

namespace irdist::sim {
namespace {

using testing::PtyHost;
using testing::WaitFor;

std::string Rig(const std::string& virtual_extra = "") {
  return "station:\n"
         "  devices:\n"
         "    slide:\n"
         "      driver: zaber_ascii\n"
         "      port: auto\n"
         "      axes: {slide: \"1 1\"}\n"
         "      origin_mm: 1000.0\n"
         "virtual:\n"
         "  devices:\n"
         "    slide:\n"
         "      microstep_um: 1.0\n"
         "      travel_mm: 2500\n"
         "      maxspeed_mm_s: 100\n"
         "      accel_mm_s2: 400\n"
         "      power_on_mm: 1500\n" +
         virtual_extra;
}

// The manual's checksum: two's complement of the 8-bit sum of the bytes after '/' or '@'.
std::string WithChecksum(const std::string& body) {
  unsigned sum = 0;
  for (unsigned char c : body) sum += c;
  char hex[3];
  std::snprintf(hex, sizeof(hex), "%02X", (256u - (sum & 0xFFu)) & 0xFFu);
  return body + ":" + hex;
}

class ZaberEmulatorTest : public ::testing::Test {
 protected:
  void SetUp() override { Open(Rig()); }
  void Open(const std::string& rig) {
    emulator_ = testing::MakeEmulator(world_, "zaber_ascii", "slide", rig);
    ASSERT_NE(emulator_, nullptr);
    host_ = std::make_unique<PtyHost>(emulator_->Start());
  }
  std::string Ask(const std::string& command) { return host_->Ask(command + "\n"); }
  bool WaitIdle() {
    return WaitFor([this] { return Ask("/1 1").find("IDLE") != std::string::npos; });
  }
  void Home() {
    ASSERT_EQ(Ask("/1 1 home"), "@01 1 OK BUSY WR 0");
    ASSERT_TRUE(WaitIdle());
  }

  World world_{20.0};
  std::unique_ptr<DeviceEmulator> emulator_;
  std::unique_ptr<PtyHost> host_;
};

TEST_F(ZaberEmulatorTest, AnswersItsIdentityAndSettings) {
  EXPECT_EQ(Ask("/1 get deviceid"), "@01 0 OK IDLE WR 50081");
  EXPECT_EQ(Ask("/get system.serial"), "@01 0 OK IDLE WR 1234567");
  EXPECT_EQ(Ask("/1 get version"), "@01 0 OK IDLE WR 7.38");
  EXPECT_EQ(Ask("/1 1 get resolution"), "@01 1 OK IDLE WR 64");
  EXPECT_EQ(Ask("/1 get system.axiscount"), "@01 0 OK IDLE WR 1");
  EXPECT_EQ(Ask("/1 set comm.alert 0"), "@01 0 OK IDLE WR 0");
  EXPECT_EQ(Ask("/1 1 get limit.min"), "@01 1 OK IDLE WR 0");
  EXPECT_EQ(Ask("/1 1 get limit.max"), "@01 1 OK IDLE WR 2500000");
  // Speed data = microsteps/s x 1.6384; acceleration data = microsteps/s^2 x 1.6384 / 10000.
  EXPECT_EQ(Ask("/1 1 get maxspeed"), "@01 1 OK IDLE WR 163840");
  EXPECT_EQ(Ask("/1 1 get accel"), "@01 1 OK IDLE WR 66");
}

TEST_F(ZaberEmulatorTest, WarnsNoReferenceUntilHomedThenHomesInSimulatedTime) {
  EXPECT_NEAR(world_.Pose().slide_mm, 1500.0, 1e-6);  // where it rests at power-up
  EXPECT_EQ(Ask("/1 1 get pos"), "@01 1 OK IDLE WR 0");
  EXPECT_EQ(Ask("/1 1 warnings"), "@01 1 OK IDLE WR 01 WR");
  const double start_s = world_.clock().Now();
  Home();
  EXPECT_GE(world_.clock().Now() - start_s, 500.0 / 100.0);  // 500 mm at <= 100 mm/s
  EXPECT_EQ(Ask("/1 1 get pos"), "@01 1 OK IDLE -- 0");
  EXPECT_NEAR(world_.Pose().slide_mm, 1000.0, 1e-9);
  EXPECT_FALSE(world_.Pose().moving);
}

TEST_F(ZaberEmulatorTest, MovesAbsoluteAndRelativeIntoTheWorld) {
  Home();
  EXPECT_EQ(Ask("/1 1 move abs 800000"), "@01 1 OK BUSY -- 0");
  EXPECT_TRUE(WaitFor([this] { return world_.Pose().moving; }));
  EXPECT_TRUE(WaitIdle());
  EXPECT_EQ(Ask("/1 1 get pos"), "@01 1 OK IDLE -- 800000");
  EXPECT_NEAR(world_.Pose().slide_mm, 1800.0, 1e-6);
  EXPECT_EQ(Ask("/1 1 move rel -300000"), "@01 1 OK BUSY -- 0");
  EXPECT_TRUE(WaitIdle());
  EXPECT_NEAR(world_.Pose().slide_mm, 1500.0, 1e-6);
  EXPECT_FALSE(world_.Pose().moving);
}

TEST_F(ZaberEmulatorTest, StopDeceleratesShortOfTheTarget) {
  Home();
  ASSERT_EQ(Ask("/1 1 move abs 2000000"), "@01 1 OK BUSY -- 0");
  EXPECT_TRUE(WaitFor([this] { return world_.Pose().slide_mm > 1100.0; }));
  EXPECT_EQ(Ask("/1 1 stop").substr(0, 9), "@01 1 OK ");
  EXPECT_TRUE(WaitIdle());
  EXPECT_LT(world_.Pose().slide_mm, 2900.0);
}

TEST_F(ZaberEmulatorTest, RejectsOutOfRangeUnknownAndMisaddressedCommands) {
  EXPECT_EQ(Ask("/1 1 move abs 2600000"), "@01 1 RJ IDLE WR BADDATA");
  EXPECT_EQ(Ask("/1 1 move abs -1"), "@01 1 RJ IDLE WR BADDATA");
  EXPECT_EQ(Ask("/1 1 move abs far"), "@01 1 RJ IDLE WR BADDATA");
  EXPECT_EQ(Ask("/1 1 frobnicate"), "@01 1 RJ IDLE WR BADCOMMAND");
  EXPECT_EQ(Ask("/1 1 get nonsense"), "@01 1 RJ IDLE WR BADCOMMAND");
  EXPECT_EQ(Ask("/1 3 get pos"), "@01 3 RJ IDLE WR BADAXIS");
  EXPECT_EQ(host_->Ask("/2 1 get pos\n", 300), "");  // another device's address: silence
}

TEST_F(ZaberEmulatorTest, EchoesMessageIdsAndVerifiesChecksums) {
  EXPECT_EQ(Ask("/1 1 12 get pos"), "@01 1 12 OK IDLE WR 0");
  // Manual, comm.checksum: a command's checksum is verified; replies carry one only once the
  // device setting is 1 (default 0).
  EXPECT_EQ(Ask("/" + WithChecksum("1 1 get pos")), "@01 1 OK IDLE WR 0");
  EXPECT_EQ(Ask("/1 1 get pos:00").substr(0, 24), "@01 1 RJ IDLE WR BADDATA");
  EXPECT_EQ(Ask("/1 get comm.checksum"), "@01 0 OK IDLE WR 0");
  EXPECT_EQ(Ask("/1 set comm.checksum 1"), "@" + WithChecksum("01 0 OK IDLE WR 0"));
  EXPECT_EQ(Ask("/1 1 get pos"), "@" + WithChecksum("01 1 OK IDLE WR 0"));
  EXPECT_EQ(Ask("/1 set comm.checksum 2"), "@" + WithChecksum("01 0 RJ IDLE WR BADDATA"));
  emulator_->PowerCycle();  // a non-volatile setting
  EXPECT_EQ(Ask("/1 get comm.checksum"), "@" + WithChecksum("01 0 OK IDLE WR 1"));
}

TEST(ZaberEmulatorFaults, OneFlippedBitInTheChosenReply) {
  World world(20.0);
  // "1651" -> "16=1": bit 3 of the byte before last of the reply to `get accel`, once.
  auto emulator = testing::MakeEmulator(world, "zaber_ascii", "slide",
                                        Rig("      flip_reply: get accel\n"
                                            "      flip_byte: -2\n"
                                            "      flip_bit: 3\n"));
  ASSERT_NE(emulator, nullptr);
  PtyHost host(emulator->Start());
  EXPECT_EQ(host.Ask("/1 1 set accel 1651\n"), "@01 1 OK IDLE WR 0");
  EXPECT_EQ(host.Ask("/1 1 get accel\n"), "@01 1 OK IDLE WR 16=1");
  EXPECT_EQ(host.Ask("/1 1 get accel\n"), "@01 1 OK IDLE WR 1651");  // flip_count 1
  EXPECT_THROW(testing::MakeEmulator(world, "zaber_ascii", "slide", Rig("      flip_bit: 8\n")),
               InputError);
}

TEST_F(ZaberEmulatorTest, SettingsChangeTheMotion) {
  EXPECT_EQ(Ask("/1 1 set maxspeed 327680"), "@01 1 OK IDLE WR 0");
  EXPECT_EQ(Ask("/1 1 get maxspeed"), "@01 1 OK IDLE WR 327680");
  EXPECT_EQ(Ask("/1 1 set maxspeed 0"), "@01 1 RJ IDLE WR BADDATA");
  EXPECT_EQ(Ask("/1 1 set limit.max 1000000"), "@01 1 OK IDLE WR 0");
  EXPECT_EQ(Ask("/1 1 move abs 1500000"), "@01 1 RJ IDLE WR BADDATA");
}

TEST_F(ZaberEmulatorTest, DropsGarblesAndDelaysRepliesOnRequest) {
  EmulatorFaults faults;
  faults.drop_rate = 1.0;
  emulator_->SetFaults(faults);
  EXPECT_EQ(host_->Ask("/1 1 get pos\n", 300), "");
  faults = EmulatorFaults();
  faults.garble_rate = 1.0;
  emulator_->SetFaults(faults);
  const std::string garbled = Ask("/1 1 get pos");
  EXPECT_EQ(garbled.size(), std::string("@01 1 OK IDLE WR 0").size());
  EXPECT_NE(garbled, "@01 1 OK IDLE WR 0");
  faults = EmulatorFaults();
  faults.delay_rate = 1.0;
  faults.delay_s = 4.0;  // 0.2 s of host time at 20x
  emulator_->SetFaults(faults);
  const double start_s = world_.clock().Now();
  EXPECT_EQ(Ask("/1 1 get pos"), "@01 1 OK IDLE WR 0");
  EXPECT_GE(world_.clock().Now() - start_s, 4.0);
}

TEST_F(ZaberEmulatorTest, AStuckAxisStallsWithTheFsFlag) {
  Home();
  EmulatorFaults faults;
  faults.stuck_axis = "slide";
  emulator_->SetFaults(faults);
  EXPECT_EQ(Ask("/1 1 move abs 500000"), "@01 1 OK BUSY -- 0");
  EXPECT_TRUE(WaitIdle());
  EXPECT_EQ(Ask("/1 1 get pos"), "@01 1 OK IDLE FS 0");
  EXPECT_NEAR(world_.Pose().slide_mm, 1000.0, 1e-9);
  EXPECT_EQ(Ask("/1 1 warnings clear"), "@01 1 OK IDLE -- 01 FS");  // read, then cleared
  EXPECT_EQ(Ask("/1 1 get pos"), "@01 1 OK IDLE -- 0");
}

TEST_F(ZaberEmulatorTest, PowerCycleMidMoveLosesTheReference) {
  Home();
  EmulatorFaults faults;
  faults.power_cycle_after_s = 2.0;
  emulator_->SetFaults(faults);
  ASSERT_EQ(Ask("/1 1 move abs 2000000"), "@01 1 OK BUSY -- 0");
  EXPECT_TRUE(WaitFor([this] { return Ask("/1 1").find("WR") != std::string::npos; }));
  EXPECT_EQ(Ask("/1 1 get pos"), "@01 1 OK IDLE WR 0");  // counts from where it stopped
  const double slide_mm = world_.Pose().slide_mm;
  EXPECT_GT(slide_mm, 1000.0);
  EXPECT_LT(slide_mm, 3000.0);
  emulator_->PowerCycle();  // also on demand
  EXPECT_EQ(Ask("/1 1 get pos"), "@01 1 OK IDLE WR 0");
}

// reset_s: after a power cycle the controller boots, deaf and mute (a command sent meanwhile is
// lost, never answered later); power_up_alert: when it is up it sends the manual's alert with the
// reference lost, then answers as usual.
TEST_F(ZaberEmulatorTest, APowerCycleBootsDeafAndMuteThenAlerts) {
  Open(Rig("      reset_s: 20\n      power_up_alert: true\n"));  // 1 s at this time scale
  Home();
  emulator_->PowerCycle();
  EXPECT_EQ(host_->Ask("/1 1 get pos\n", 300), "");
  EXPECT_EQ(host_->ReadLine(3000), "!01 0 IDLE WR");
  EXPECT_EQ(host_->ReadLine(300), "");  // the command sent during the boot stays unanswered
  EXPECT_EQ(Ask("/1 1 get pos"), "@01 1 OK IDLE WR 0");
}

TEST(ZaberEmulatorRig, FaultsComeFromTheRigFile) {
  World world(20.0);
  auto emulator = testing::MakeEmulator(world, "zaber_ascii", "slide",
                                        Rig("      drop_rate: 1.0\n      stuck_axis: slide\n"));
  ASSERT_NE(emulator, nullptr);
  PtyHost host(emulator->Start());
  EXPECT_EQ(host.Ask("/1 1 get pos\n", 300), "");
  EmulatorFaults faults;
  faults.stuck_axis = "slide";
  emulator->SetFaults(faults);
  EXPECT_EQ(host.Ask("/1 1 get pos\n"), "@01 1 OK IDLE WR 0");
  EXPECT_THROW(testing::MakeEmulator(world, "zaber_ascii", "slide", Rig("      drop_rate: 2\n")),
               InputError);
  EXPECT_THROW(testing::MakeEmulator(world, "zaber_ascii", "slide",
                                     Rig("      stuck_axis: roll\n")),
               InputError);
}

TEST(ZaberEmulatorRig, UnknownVirtualKeysAreErrorsWithTheLine) {
  World world(1.0);
  try {
    testing::MakeEmulator(world, "zaber_ascii", "slide", Rig("      speed_mm_s: 3\n"));
    FAIL() << "an unknown key was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.File(), "inline-rig.yaml");
    EXPECT_GT(e.Line(), 0);
    EXPECT_NE(std::string(e.what()).find("speed_mm_s"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace irdist::sim
