#include "sim/station_model.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

// The station model driven directly in simulated time: no pty, no thread, no wall clock. The
// expected replies come from docs/station-protocol.md (states, error codes, units of 0.01).

namespace irdist::sim {
namespace {

struct RecordedEffects : StationEffects {
  double slide_mm = -1, pan_deg = -1, tilt_deg = -1, bias_ma = -1;
  bool moving = false;
  int pulses = 0, power_ups = 0;
  void SetPose(double s, double p, double t, bool m) override {
    slide_mm = s;
    pan_deg = p;
    tilt_deg = t;
    moving = m;
  }
  void SetCurrent(double ma) override { bias_ma = ma; }
  void FireTrigger() override { ++pulses; }
  void PoweredUp() override { ++power_ups; }
};

class StationModelTest : public ::testing::Test {
 protected:
  explicit StationModelTest(EmulatorOptions options = {}) : model_(effects_, options) {
    model_.PowerOn(0.0);
  }
  std::string Do(const std::string& command) { return model_.Execute(command, now_s_); }
  // Advances simulated time in 1 ms steps (as the pty thread's loop would).
  void RunFor(double seconds) {
    const double end_s = now_s_ + seconds;
    while (now_s_ < end_s) {
      now_s_ += 0.001;
      model_.Advance(now_s_);
    }
  }
  std::string State() {
    const std::string reply = Do("STAT?");
    return reply.substr(0, reply.find(','));
  }
  void Home() {
    ASSERT_EQ(Do("HOME"), "OK");
    RunFor(30.0);
    ASSERT_EQ(State(), "OK IDLE");
  }

  RecordedEffects effects_;
  StationModel model_;
  double now_s_ = 0.0;
};

TEST_F(StationModelTest, PowersUpUnhomedWithAPowerOnErrorAndRefusesMovesUntilHomed) {
  EXPECT_EQ(State(), "OK UNHOMED");
  EXPECT_EQ(effects_.power_ups, 1);
  EXPECT_EQ(effects_.bias_ma, 0.0);
  EXPECT_EQ(Do("SYST:ERR?"), "OK -500,\"Power on\"");
  EXPECT_EQ(Do("SYST:ERR?"), "OK 0,\"No error\"");
  EXPECT_EQ(Do("MOVE 150000,0,0"), "ERR 201,\"Not homed\"");
  EXPECT_EQ(Do("SYST:ERR?"), "OK 201,\"Not homed\"");
  EXPECT_EQ(Do("FOO"), "ERR -113,\"Undefined header\"");
  EXPECT_EQ(Do("MOVE 1,2"), "ERR -109,\"Missing parameter\"");
  EXPECT_EQ(Do("MOVE 1,2,x"), "ERR -104,\"Data type error\"");
}

TEST_F(StationModelTest, HomesThenMovesAlongItsProfileAndSettlesAtTheTarget) {
  Home();
  EXPECT_EQ(Do("POS?"), "OK 100000,0,0");  // the rig's home: slide 1000 mm, pan 0, tilt 0
  EXPECT_DOUBLE_EQ(effects_.slide_mm, 1000.0);
  ASSERT_EQ(Do("MOVE 150000,1000,-500"), "OK");
  EXPECT_EQ(State(), "OK MOVING");
  EXPECT_EQ(Do("MOVE 160000,0,0"), "ERR -221,\"Settings conflict\"");  // busy
  EXPECT_EQ(Do("MOVE 150000,1000,-500"), "OK");  // the same target again: idempotent
  RunFor(0.5);
  EXPECT_TRUE(effects_.moving);
  EXPECT_GT(effects_.slide_mm, 1000.0);
  EXPECT_LT(effects_.slide_mm, 1500.0);
  RunFor(10.0);
  EXPECT_EQ(State(), "OK IDLE");
  EXPECT_EQ(Do("POS?"), "OK 150000,1000,-500");
  EXPECT_FALSE(effects_.moving);
  EXPECT_DOUBLE_EQ(effects_.pan_deg, 10.0);
  EXPECT_DOUBLE_EQ(effects_.tilt_deg, -5.0);
  EXPECT_EQ(Do("MOVE 400000,0,0"), "ERR -222,\"Data out of range\"");  // past the soft limit
}

TEST_F(StationModelTest, EmergencyStopTurnsTheIredOffAndOnlyAllowsTurningItOff) {
  ASSERT_EQ(Do("SOUR:CURR 12345"), "OK");
  EXPECT_DOUBLE_EQ(effects_.bias_ma, 123.45);
  EXPECT_EQ(Do("SOUR:CURR?"), "OK 12345");
  model_.PressEmergencyStop(now_s_);
  EXPECT_EQ(State(), "OK ESTOP");
  EXPECT_EQ(effects_.bias_ma, 0.0);
  EXPECT_EQ(Do("SOUR:CURR 100"), "ERR 202,\"Emergency stop active\"");
  EXPECT_EQ(Do("SOUR:CURR 0"), "OK");
  EXPECT_EQ(Do("HOME"), "ERR 202,\"Emergency stop active\"");
  EXPECT_EQ(Do("ESTOP:CLR"), "OK");
  EXPECT_EQ(State(), "OK UNHOMED");
}

TEST_F(StationModelTest, TriggerTrainFiresTheCountedPulsesAtThePeriod) {
  ASSERT_EQ(Do("TRIG:COUN 3"), "OK");
  ASSERT_EQ(Do("TRIG:PER 20000"), "OK");  // 20 ms
  ASSERT_EQ(Do("TRIG:FIRE"), "OK");
  ASSERT_TRUE(model_.NextPulseS().has_value());
  RunFor(0.030);  // pulses at 0.001 and 0.021 s; the third is due at 0.041 s
  EXPECT_EQ(effects_.pulses, 2);
  EXPECT_EQ(Do("TRIG:FIRE"), "ERR -221,\"Settings conflict\"");
  RunFor(0.100);
  EXPECT_EQ(effects_.pulses, 3);
  EXPECT_FALSE(model_.NextPulseS().has_value());
  EXPECT_EQ(Do("TRIG:PULS?"), "OK 3,0");
}

TEST_F(StationModelTest, ErrorQueueKeepsSixteenEntriesTheLastBeingTheOverflow) {
  ASSERT_EQ(Do("*CLS"), "OK");
  for (int i = 0; i < 20; ++i) Do("NOPE");
  std::vector<std::string> errors;
  for (int i = 0; i < 17; ++i) errors.push_back(Do("SYST:ERR?"));
  EXPECT_EQ(errors[0], "OK -113,\"Undefined header\"");
  EXPECT_EQ(errors[14], "OK -113,\"Undefined header\"");
  EXPECT_EQ(errors[15], "OK -350,\"Queue overflow\"");
  EXPECT_EQ(errors[16], "OK 0,\"No error\"");
}

TEST_F(StationModelTest, LinkWatchdogTurnsTheIredOffWhenTheHostFallsSilent) {
  ASSERT_EQ(Do("SYST:WDOG 1"), "OK");
  ASSERT_EQ(Do("SOUR:CURR 5000"), "OK");
  model_.NoteValidRequest(now_s_);
  RunFor(0.9);
  EXPECT_DOUBLE_EQ(effects_.bias_ma, 50.0);
  RunFor(0.2);
  EXPECT_EQ(effects_.bias_ma, 0.0);
  EXPECT_EQ(Do("SYST:WDOG?"), "OK 0");
  EXPECT_EQ(Do("SYST:ERR?"), "OK -500,\"Power on\"");
  EXPECT_EQ(Do("SYST:ERR?"), "OK 206,\"Link lost\"");
}

TEST_F(StationModelTest, RebootDuringAMoveStopsTheAxesAndComesBackUnhomedWithANewBootId) {
  Home();
  const std::string boot_id = model_.BootId();
  model_.RebootDuringNextMove(0.5);
  ASSERT_EQ(Do("MOVE 300000,0,0"), "OK");
  RunFor(0.6);
  EXPECT_EQ(model_.Reboots(), 1u);
  EXPECT_NE(model_.BootId(), boot_id);
  EXPECT_EQ(effects_.power_ups, 2);
  EXPECT_TRUE(model_.Booting());
  RunFor(0.3);  // the boot time passes
  EXPECT_EQ(State(), "OK UNHOMED");
  EXPECT_GT(effects_.slide_mm, 1000.0);  // stopped where the power went, short of the target
  EXPECT_LT(effects_.slide_mm, 3000.0);
}

EmulatorOptions WithFault(const std::string& fault, const std::string& stuck = "") {
  EmulatorOptions o;
  o.fault_at_move = fault.empty() ? 0 : 1;
  o.fault = fault;
  o.stuck_axis = stuck;
  return o;
}

class StationModelRefuseTest : public StationModelTest {
 protected:
  StationModelRefuseTest() : StationModelTest(WithFault("refuse")) {}
};
TEST_F(StationModelRefuseTest, RefusesTheFaultedMoveOnlyAndAcceptsTheNext) {
  Home();
  EXPECT_EQ(Do("MOVE 150000,0,0"), "ERR -222,\"Data out of range\"");
  EXPECT_EQ(Do("MOVE 150000,0,0"), "OK");
}

class StationModelSilentTest : public StationModelTest {
 protected:
  StationModelSilentTest() : StationModelTest(WithFault("silent")) {}
};
TEST_F(StationModelSilentTest, SilentFaultMarksTheModelSilentAfterTheMove) {
  Home();
  EXPECT_FALSE(model_.Silent());
  EXPECT_EQ(Do("MOVE 150000,0,0"), "OK");
  EXPECT_TRUE(model_.Silent());
}

class StationModelStuckTest : public StationModelTest {
 protected:
  StationModelStuckTest() : StationModelTest(WithFault("", "slide")) {}
};
TEST_F(StationModelStuckTest, AStuckSlideFailsHomingWithError204) {
  ASSERT_EQ(Do("*CLS"), "OK");
  ASSERT_EQ(Do("HOME"), "OK");
  RunFor(30.0);
  EXPECT_EQ(State(), "OK UNHOMED");
  EXPECT_EQ(Do("SYST:ERR?"), "OK 204,\"Homing failed\"");
  EXPECT_DOUBLE_EQ(effects_.slide_mm, 2000.0);  // never left its power-on position
}

EmulatorOptions WithSlideMaxSpeed(double max_speed_mm_s) {
  EmulatorOptions o;
  o.slide.max_speed = max_speed_mm_s;
  return o;
}

class StationModelSpeedTest : public StationModelTest {
 protected:
  StationModelSpeedTest() : StationModelTest(WithSlideMaxSpeed(600.0)) {}
};

// SPEED (docs/station-protocol.md section 5): the cruise speed of the moves that follow, within
// [0.01 unit/s, max_speed]; the power-up speed again after a reboot.
TEST_F(StationModelSpeedTest, SetsTheCruiseSpeedOfTheNextMovesWithinTheAxissFastest) {
  Home();
  EXPECT_EQ(Do("SPEED?"), "OK 20000,3000,3000");  // the options' speeds at power-up
  EXPECT_EQ(Do("SPEED SLIDE,60001"), "ERR -222,\"Data out of range\"");  // past max_speed
  EXPECT_EQ(Do("SPEED PAN,3001"), "ERR -222,\"Data out of range\"");  // pan: max_speed 0 = speed
  EXPECT_EQ(Do("SPEED SLIDE,0"), "ERR -222,\"Data out of range\"");
  EXPECT_EQ(Do("SPEED ROLL,100"), "ERR -104,\"Data type error\"");
  EXPECT_EQ(Do("SPEED SLIDE"), "ERR -109,\"Missing parameter\"");
  ASSERT_EQ(Do("SPEED slide,50000"), "OK");
  EXPECT_EQ(Do("SPEED?"), "OK 50000,3000,3000");
  // 1000 mm at 500 mm/s and 400 mm/s^2: 1.25 s up, 0.75 s cruising, 1.25 s down (3.25 s; at
  // the power-up's 200 mm/s it would take 5.5 s).
  ASSERT_EQ(Do("MOVE 200000,0,0"), "OK");
  RunFor(1.25 + 0.375);
  EXPECT_NEAR(effects_.slide_mm, 1000.0 + 312.5 + 187.5, 1.0);  // mid-cruise: 1500 mm
  RunFor(1.625 + 0.2);
  EXPECT_EQ(State(), "OK IDLE");
  EXPECT_EQ(Do("POS?"), "OK 200000,0,0");
  model_.Reboot(now_s_);
  RunFor(1.0);
  EXPECT_EQ(Do("SPEED?"), "OK 20000,3000,3000");
}

TEST(StationModelOptions, RejectsInvalidOptionsAtConstruction) {
  RecordedEffects effects;
  EmulatorOptions o;
  o.fault = "explode";
  EXPECT_ANY_THROW(StationModel(effects, o));
}

}  // namespace
}  // namespace irdist::sim
