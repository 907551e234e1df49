// The flir_ptu driver against a scripted PTU-E unit (replies shaped as the command reference's
// examples: "* 22" in terse mode, "! Maximum allowable Pan position is 3090" on an error).

#include <gtest/gtest.h>

#include <cmath>
#include <thread>

#include "base/input_error.h"
#include "sim/device_emulator.h"
#include "sim/world.h"
#include "station/driver.h"
#include "station/serial_transport.h"
#include "tests/station/fake_transport.h"
#include "tests/station/rig_fixture.h"

namespace irdist {
namespace {

// One axis of the unit: moves 100 positions per poll of its position.
struct PtuAxisModel {
  long long pos = 0, target = 0, min = -3090, max = 3090;
  double resolution_arcsec = 185.1428;
  long long speed = 1000, accel = 2000;
  bool stuck = false;
  void Step() {
    if (stuck) return;
    const long long d = target - pos;
    pos += std::abs(d) <= 100 ? d : (d > 0 ? 100 : -100);
  }
};

struct Ptu {
  PtuAxisModel pan, tilt;
  bool echo = true, terse = false;
  std::string version = "Pan-Tilt Controller v3.2.0, (C)2010 FLIR Motion Control Systems, Inc.";
  std::vector<std::string> commands;
  int drop_next = 0;
  int wrong_positions = 0;  // position replies with a damaged digit

  PtuAxisModel& Of(char c) { return c == 'P' ? pan : tilt; }
  std::string Value(long long v, const std::string& what) const {
    return terse ? "* " + std::to_string(v) : "* " + what + " is " + std::to_string(v);
  }
  std::string Answer(const std::string& c) {
    if (c == "ED") { echo = false; return "*"; }
    if (c == "FT") { terse = true; return "*"; }
    if (c == "V") return "* " + version;
    if (c == "I" || c == "H") return "*";
    if (c == "A") {  // await: answers once both axes stand still
      for (PtuAxisModel* a : {&pan, &tilt}) {
        while (!a->stuck && a->pos != a->target) a->Step();
      }
      return "*";
    }
    if (c == "R") {
      pan.target = tilt.target = 0;
      pan.pos = 1500;  // the reset swept the axes to their limits; they come back on polls
      return "*";
    }
    if (c.size() < 2 || (c[0] != 'P' && c[0] != 'T')) return "! Illegal command";
    PtuAxisModel& a = Of(c[0]);
    const std::string rest = c.substr(2);
    switch (c[1]) {
      case 'R': return terse ? "* " + std::to_string(a.resolution_arcsec)
                             : "* resolution is " + std::to_string(a.resolution_arcsec);
      case 'N': return Value(a.min, "Minimum position");
      case 'X': return Value(a.max, "Maximum position");
      case 'S':
        if (rest.empty()) return Value(a.speed, "speed");
        a.speed = std::stoll(rest);
        return "*";
      case 'A':
        if (rest.empty()) return Value(a.accel, "acceleration");
        a.accel = std::stoll(rest);
        return "*";
      case 'P': {
        if (rest.empty()) {
          a.Step();
          if (wrong_positions > 0) {
            --wrong_positions;
            return Value(a.pos + 1000, "Current position");
          }
          return Value(a.pos, "Current position");
        }
        const long long t = std::stoll(rest);
        if (t > a.max || t < a.min) return "! Maximum allowable position is " + std::to_string(a.max);
        a.target = t;
        return "*";
      }
    }
    return "! Illegal command";
  }
  std::vector<std::string> Respond(const std::string& c) {
    commands.push_back(c);
    std::string reply = Answer(c);
    if (echo) reply = c + " " + reply;
    if (drop_next > 0) {
      --drop_next;
      return {};
    }
    return {reply};
  }
  void PowerCycle() {  // power-up reset: back at 0, default speed, echo on, verbose
    pan = PtuAxisModel{};
    tilt = PtuAxisModel{};
    echo = true;
    terse = false;
  }
};

DeviceSpec HeadSpec() {
  DeviceSpec spec = FakeDeviceSpec("head", "flir_ptu", "/dev/ttyUSB1", 10);
  spec.axes[Axis::kPan] = "pan";
  spec.axes[Axis::kTilt] = "tilt";
  return spec;
}

struct Head : FakeDeviceBench<Ptu> {
  Ptu& ptu = device;
  Motion* motion = driver->motion();
  explicit Head(const DeviceSpec& spec = HeadSpec()) : FakeDeviceBench("flir_ptu", spec) {}
  int Count(const std::string& command) const {
    return static_cast<int>(std::count(ptu.commands.begin(), ptu.commands.end(), command));
  }
};

constexpr double kDegPerPos = 185.1428 / 3600.0;

TEST(FlirPtu, RegistersAsMotionDriverWithEnterDelimiter) {
  const DriverInfo* info = FindDriver("flir_ptu");
  ASSERT_NE(info, nullptr);
  EXPECT_EQ(info->line_end, "\r");
  EXPECT_EQ(info->roles, std::vector<std::string>{"motion"});
}

TEST(FlirPtu, IdentifyReadsVersionResolutionLimitsAndSpeed) {
  Head h;
  const DeviceIdentity id = h.motion->Identify();
  EXPECT_NE(id.firmware.find("Pan-Tilt Controller v3.2.0"), std::string::npos);
  EXPECT_FALSE(h.ptu.echo);
  EXPECT_TRUE(h.ptu.terse);
  const AxisSpeed pan = h.motion->Speed(Axis::kPan);
  EXPECT_NEAR(pan.speed, 1000 * kDegPerPos, 1e-9);
  EXPECT_NEAR(pan.acceleration, 2000 * kDegPerPos, 1e-9);
  EXPECT_EQ(h.motion->Axes().size(), 2u);
}

TEST(FlirPtu, WrongDeviceIsADeviceErrorBeforeAnythingMoves) {
  Head h;
  h.wire->respond = [](const std::string&) {
    return std::vector<std::string>{"@01 0 OK IDLE -- 0"};
  };
  EXPECT_THROW(h.motion->Identify(), DeviceError);
  Head other;
  other.ptu.version = "Some Other Controller 1.0";
  EXPECT_THROW(other.motion->Identify(), DeviceError);
  EXPECT_EQ(other.Count("R"), 0);
}

TEST(FlirPtu, RigSpeedIsSetInPositionsPerSecond) {
  DeviceSpec spec = HeadSpec();
  spec.settings["speed_deg_s"] = {"30", 12};
  Head h(spec);
  h.motion->Identify();
  EXPECT_EQ(h.ptu.pan.speed, std::llround(30 / kDegPerPos));
  EXPECT_NEAR(h.motion->Speed(Axis::kPan).speed, std::llround(30 / kDegPerPos) * kDegPerPos, 1e-9);
}

TEST(FlirPtu, HomesThenMovesInDegrees) {
  Head h;
  h.motion->Identify();
  EXPECT_EQ(h.motion->State(), MotionState::kUnhomed);
  h.motion->Home();
  EXPECT_EQ(h.Count("R"), 1);
  EXPECT_EQ(h.ptu.pan.pos, 0);
  StationPosition target;
  target.pan_deg = 20.0;
  target.tilt_deg = -10.0;
  h.motion->StartMove(target);
  EXPECT_EQ(h.ptu.pan.target, std::llround(20.0 / kDegPerPos));
  EXPECT_EQ(h.ptu.tilt.target, std::llround(-10.0 / kDegPerPos));
  h.motion->WaitSettled(std::chrono::milliseconds(10000));
  StationPosition now;
  h.motion->ReadPosition(&now);
  EXPECT_NEAR(now.pan_deg, 20.0, kDegPerPos);
  EXPECT_NEAR(now.tilt_deg, -10.0, kDegPerPos);
  EXPECT_EQ(h.motion->State(), MotionState::kIdle);
  h.motion->CheckAlive();
}

TEST(FlirPtu, TargetBeyondTheLimitsIsRefusedBeforeSending) {
  Head h;
  h.motion->Identify();
  h.motion->Home();
  StationPosition target;
  target.pan_deg = 170.0;  // beyond 3090 positions = 158.9 deg
  EXPECT_THROW(h.motion->StartMove(target), DeviceError);
  EXPECT_EQ(h.Count("PP" + std::to_string(std::llround(170.0 / kDegPerPos))), 0);
}

TEST(FlirPtu, ErrorReplyIsADeviceErrorWithTheUnitsText) {
  Head h;
  h.motion->Identify();
  h.motion->Home();
  h.ptu.pan.max = 100;  // the unit's limits narrowed behind the driver's back
  StationPosition target;
  target.pan_deg = 20.0;
  try {
    h.motion->StartMove(target);
    FAIL() << "expected DeviceError";
  } catch (const DeviceError& e) {
    EXPECT_EQ(e.device_code(), "!Maximum allowable position is 100");
  }
}

TEST(FlirPtu, DroppedQueryRepliesAreRetried) {
  Head h;
  h.motion->Identify();
  h.ptu.drop_next = 2;
  StationPosition now;
  h.motion->ReadPosition(&now);
  EXPECT_NEAR(now.pan_deg, 0.0, 1e-12);
}

// A reset whose '*' never comes (lost or garbled) stops homing with a LinkError that names the
// driver, the rig entry and the port.
TEST(FlirPtu, AResetNeverAcknowledgedIsALinkErrorNamingTheDevice) {
  DeviceSpec spec = HeadSpec();
  spec.settings["home_timeout_s"] = {"0.2", 30};
  Head h(spec);
  h.motion->Identify();
  h.ptu.drop_next = 1;  // the R's '*'
  try {
    h.motion->Home();
    FAIL() << "expected LinkError";
  } catch (const LinkError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("flir_ptu 'head'"), std::string::npos) << what;
    EXPECT_NE(what.find("reset (R)"), std::string::npos) << what;
    EXPECT_NE(what.find("/dev/ttyUSB1"), std::string::npos) << what;
  }
}

TEST(FlirPtu, ReportedPositionIsReadTwiceAlike) {
  Head h;
  h.motion->Identify();
  h.ptu.wrong_positions = 1;
  StationPosition now;
  h.motion->ReadPosition(&now);
  EXPECT_NEAR(now.pan_deg, 0.0, 1e-12);
}

TEST(FlirPtu, LateReplyIsNotTakenForTheNextCommands) {
  Head h;
  h.motion->Identify();
  h.motion->Home();
  StationPosition target;
  target.pan_deg = 20.0;
  target.tilt_deg = 5.0;
  h.motion->StartMove(target);
  h.motion->WaitSettled(std::chrono::milliseconds(10000));
  // A reply to an earlier query arrives late, before the next command is sent.
  h.wire->pending.push_back("* 9999");
  EXPECT_EQ(h.motion->State(), MotionState::kIdle);  // one position read per axis
}

TEST(FlirPtu, LostMoveAcknowledgementIsNotResentWhenTheAxisMoves) {
  Head h;
  h.motion->Identify();
  h.motion->Home();
  h.ptu.drop_next = 1;
  StationPosition target;
  target.pan_deg = 30.0;
  h.motion->StartMove(target);
  h.motion->WaitSettled(std::chrono::milliseconds(10000));
  EXPECT_EQ(h.Count("PP" + std::to_string(std::llround(30.0 / kDegPerPos))), 1);
}

TEST(FlirPtu, StuckAxisTimesOutWithADeviceError) {
  Head h;
  h.motion->Identify();
  h.motion->Home();
  h.ptu.tilt.stuck = true;
  StationPosition target;
  target.tilt_deg = 10.0;
  h.motion->StartMove(target);
  try {
    h.motion->WaitSettled(std::chrono::milliseconds(60000));  // ends early: it stands still
    FAIL() << "expected DeviceError";
  } catch (const DeviceError& e) {
    EXPECT_NE(std::string(e.what()).find("stopped short: tilt"), std::string::npos) << e.what();
  }
  EXPECT_GE(h.Count("H"), 1);  // halted
}

TEST(FlirPtu, HomingAfterAPowerCycleRestoresTheRigSpeed) {
  DeviceSpec spec = HeadSpec();
  spec.settings["speed_deg_s"] = {"30", 12};
  Head h(spec);
  h.motion->Identify();
  h.motion->Home();
  h.ptu.PowerCycle();
  EXPECT_THROW(h.motion->CheckAlive(), DeviceRestarted);
  h.motion->Home();
  EXPECT_EQ(h.ptu.pan.speed, std::llround(30 / kDegPerPos));
  StationPosition target;
  target.pan_deg = 10.0;
  h.motion->StartMove(target);
  h.motion->WaitSettled(std::chrono::milliseconds(10000));
  h.motion->CheckAlive();
}

TEST(FlirPtu, PowerCycleDuringAMoveIsARestart) {
  Head h;
  h.motion->Identify();
  h.motion->Home();
  StationPosition target;
  target.pan_deg = 20.0;
  h.motion->StartMove(target);
  h.motion->WaitSettled(std::chrono::milliseconds(10000));
  target.pan_deg = 40.0;
  h.motion->StartMove(target);
  h.ptu.PowerCycle();  // the power-up reset leaves the unit at 0/0
  EXPECT_THROW(h.motion->WaitSettled(std::chrono::milliseconds(60000)), DeviceRestarted);
}

TEST(FlirPtu, PowerCycleIsARestart) {
  Head h;
  h.motion->Identify();
  h.motion->Home();
  StationPosition target;
  target.pan_deg = 10.0;
  h.motion->StartMove(target);
  h.motion->WaitSettled(std::chrono::milliseconds(10000));
  h.ptu.PowerCycle();
  EXPECT_THROW(h.motion->CheckAlive(), DeviceRestarted);
  EXPECT_EQ(h.motion->State(), MotionState::kUnhomed);
}

// --- Against the PTU emulator (sim/ptu_emulator.cc, written from the manual) over a real pty.

std::string EmulatedRig(const std::string& virtual_extra) {
  return "station:\n"
         "  devices:\n"
         "    head:\n"
         "      driver: flir_ptu\n"
         "      port: auto\n"
         "      axes: {pan: pan, tilt: tilt}\n"
         "virtual:\n"
         "  devices:\n"
         "    head:\n"
         "      verbose: true\n" +
         virtual_extra;
}

// The emulator on a World in real time, and drivers opened on its pty as the Station opens them
// (line end and CR-ended replies from the driver's registration).
struct EmulatedHead {
  explicit EmulatedHead(const std::string& virtual_extra)
      : emulator(sim::FindEmulator("flir_ptu")->create(
            world, {"head", "flir_ptu", "inline.yaml", EmulatedRig(virtual_extra), 1})) {
    port = emulator->Start();
  }
  std::unique_ptr<DeviceDriver> Open(DeviceSpec spec) {
    const DriverInfo* info = FindDriver("flir_ptu");
    SerialOptions serial;
    serial.baud = info->default_baud;
    serial.line_end = info->line_end;
    serial.cr_ends_line = info->cr_ends_reply;
    spec.port = port;
    return info->create(spec, std::make_unique<SerialTransport>(port, serial));
  }
  static DeviceSpec Spec() {
    DeviceSpec spec = HeadSpec();
    spec.reply_timeout_ms = 100;
    spec.settings["retries"] = {"2", 11};
    spec.settings["reset_wait_s"] = {"10", 12};
    return spec;
  }
  sim::World world{1.0};
  std::unique_ptr<sim::DeviceEmulator> emulator;
  std::string port;
};

// The manuals' replies end with CR alone: read as lines.
TEST(FlirPtuEmulated, RepliesEndingWithCrAloneAreRead) {
  EmulatedHead head("      reply_line_end: cr\n");
  std::unique_ptr<DeviceDriver> driver = head.Open(EmulatedHead::Spec());
  EXPECT_NE(driver->motion()->Identify().firmware.find("Pan-Tilt"), std::string::npos);
  driver->motion()->Home();
  StationPosition target;
  target.pan_deg = 10.0;
  driver->motion()->StartMove(target);
  driver->motion()->WaitSettled(std::chrono::milliseconds(20000));
  EXPECT_NEAR(head.world.Pose().pan_deg, 10.0, 0.03);
}

// A power cycle whose reset lasts longer than every retry of a query (3 x 100 ms here): the
// driver waits for the unit (up to reset_wait_s) and sees the restart, not a dead link.
TEST(FlirPtuEmulated, AResetLongerThanTheRetriesIsWaitedFor) {
  EmulatedHead head("      reset_s: 1.0\n      reset_on_power_up: true\n");
  DeviceSpec spec = EmulatedHead::Spec();
  spec.settings["speed_deg_s"] = {"40", 13};
  std::unique_ptr<DeviceDriver> driver = head.Open(spec);
  driver->motion()->Identify();
  driver->motion()->Home();
  StationPosition target;
  target.pan_deg = 10.0;
  driver->motion()->StartMove(target);
  driver->motion()->WaitSettled(std::chrono::milliseconds(20000));
  head.emulator->PowerCycle();
  EXPECT_THROW(driver->motion()->CheckAlive(), DeviceRestarted);
}

// A run gives up while the unit resets (its queries queued in the unit); a new session at once
// reads their stale answers away and identifies the unit.
TEST(FlirPtuEmulated, ANewSessionReadsStaleRepliesAwayBeforeIdentifying) {
  EmulatedHead head("      reset_s: 1.0\n");
  DeviceSpec impatient = EmulatedHead::Spec();
  impatient.settings["reset_wait_s"] = {"0.05", 12};
  std::this_thread::sleep_for(std::chrono::milliseconds(1200));  // the power-up reset
  {
    std::unique_ptr<DeviceDriver> first = head.Open(impatient);
    first->motion()->Identify();
    head.emulator->PowerCycle();
    StationPosition p;
    EXPECT_THROW(first->motion()->ReadPosition(&p), LinkError);
  }
  std::unique_ptr<DeviceDriver> next = head.Open(EmulatedHead::Spec());
  EXPECT_NE(next->motion()->Identify().firmware.find("Pan-Tilt"), std::string::npos);
  StationPosition p;
  next->motion()->ReadPosition(&p);
  EXPECT_NEAR(p.pan_deg, 0.0, 1e-9);
}

// Regression: a unit that loses power mid-run resets for longer than every retry while
// echoing commands and printing its banner and "Initializing..." (the manuals' power-up). It is
// waited for (reset_wait_s), found restarted (DeviceRestarted, not "answers, but never with a
// pan-tilt unit's version"), identified and homed again, and moves on.
TEST(FlirPtuEmulated, AResetThatEchoesAndPrintsItsBannerIsWaitedForAndHomedAgain) {
  EmulatedHead head("      reset_s: 1.5\n      echo: true\n");
  DeviceSpec spec = EmulatedHead::Spec();
  spec.settings["speed_deg_s"] = {"40", 13};
  std::unique_ptr<DeviceDriver> driver = head.Open(spec);
  Motion& motion = *driver->motion();
  motion.Identify();  // during the first power-up reset: its echo is waited out too
  motion.Home();
  StationPosition target;
  target.pan_deg = 10.0;
  motion.StartMove(target);
  motion.WaitSettled(std::chrono::milliseconds(20000));
  head.emulator->PowerCycle();
  try {
    motion.CheckAlive();
    FAIL() << "a power cycle went unseen";
  } catch (const DeviceRestarted& e) {
    EXPECT_NE(std::string(e.what()).find("home it and retake"), std::string::npos) << e.what();
  }
  EXPECT_EQ(motion.State(), MotionState::kUnhomed);
  motion.Home();  // what the sweep does on a restart
  motion.StartMove(target);
  motion.WaitSettled(std::chrono::milliseconds(20000));
  EXPECT_NEAR(head.world.Pose().pan_deg, 10.0, 0.03);
  StationPosition read;
  motion.ReadPosition(&read);
  EXPECT_NEAR(read.pan_deg, 10.0, 0.03);
}

// The same power cut in the middle of a move: the wait for the move sees the reset through and
// reports the restart; homed again, the retaken move lands.
TEST(FlirPtuEmulated, APowerCutMidMoveIsARestartOnceTheResetEnds) {
  EmulatedHead head("      reset_s: 1.5\n      echo: true\n");
  std::unique_ptr<DeviceDriver> driver = head.Open(EmulatedHead::Spec());
  Motion& motion = testing::IdentifiedAndHomed(*driver);
  StationPosition target;
  target.pan_deg = 20.0;
  target.tilt_deg = -5.0;
  motion.StartMove(target);
  head.emulator->PowerCycle();
  EXPECT_THROW(motion.WaitSettled(std::chrono::milliseconds(20000)), DeviceRestarted);
  motion.Home();
  motion.StartMove(target);
  motion.WaitSettled(std::chrono::milliseconds(20000));
  EXPECT_NEAR(head.world.Pose().pan_deg, 20.0, 0.03);
  EXPECT_NEAR(head.world.Pose().tilt_deg, -5.0, 0.03);
}

// Regression: no move ends (and so no frame is exposed) before the unit has confirmed the
// end of its last command: positions read within the rig's tolerance of the target while the
// axes still creep in (a slow deceleration) are not the end of the move, and with replies dropped
// and delayed past the reply timeout no late or lost reply is taken for the confirmation: every
// move returns with the unit at rest at its target.
TEST(FlirPtuEmulated, NoMoveEndsBeforeTheUnitConfirmsIt) {
  EmulatedHead head("      pan_accel_pos_s2: 200\n      tilt_accel_pos_s2: 200\n");
  DeviceSpec spec = EmulatedHead::Spec();
  spec.reply_timeout_ms = 250;
  spec.settings["retries"] = {"6", 11};
  spec.settings["tolerance_positions"] = {"3", 14};
  std::unique_ptr<DeviceDriver> driver = head.Open(spec);
  Motion& motion = testing::IdentifiedAndHomed(*driver);
  head.emulator->SetFaults(testing::LossyReplies(0.5));
  for (int i = 0; i < 6; ++i) {
    StationPosition target;
    target.pan_deg = (i % 2 == 0 ? 1.0 : -1.0) * (1.0 + 0.5 * i);
    target.tilt_deg = i % 3 == 0 ? 0.0 : 0.25 * i;  // some moves leave the tilt where it is
    motion.StartMove(target);
    motion.WaitSettled(std::chrono::milliseconds(20000));
    const sim::PoseState pose = head.world.Pose();
    EXPECT_FALSE(pose.moving) << "move " << i << " ended while the unit was still moving";
    EXPECT_NEAR(pose.pan_deg, target.pan_deg, 0.03) << "move " << i;
    EXPECT_NEAR(pose.tilt_deg, target.tilt_deg, 0.03) << "move " << i;
  }
}

// The unit's own "!P" (the pan axis hit a limit and lost synchrony) is reported as such.
TEST(FlirPtuEmulated, TheUnitsLimitHitReportIsSeen) {
  EmulatedHead head("      limit_hit_axis: pan\n");
  std::unique_ptr<DeviceDriver> driver = head.Open(EmulatedHead::Spec());
  driver->motion()->Identify();
  driver->motion()->Home();
  StationPosition target;
  target.pan_deg = 30.0;
  driver->motion()->StartMove(target);
  try {
    driver->motion()->WaitSettled(std::chrono::milliseconds(20000));
    FAIL() << "expected DeviceError";
  } catch (const DeviceError& e) {
    EXPECT_EQ(e.device_code(), "!P");
    EXPECT_NE(std::string(e.what()).find("pan axis hit its limit"), std::string::npos) << e.what();
  }
}

// speed_deg_s beyond the unit's speed bound (TU) is refused before it is sent, with advice about
// speed; a refused speed command gets the same kind of advice, not position limits.
TEST(FlirPtuEmulated, ASpeedBeyondTheUnitsBoundIsAboutSpeed) {
  EmulatedHead head("");
  DeviceSpec spec = EmulatedHead::Spec();
  spec.settings["speed_deg_s"] = {"200", 13};  // tilt: 200 deg/s = 15555 positions/s > 12000
  std::unique_ptr<DeviceDriver> driver = head.Open(spec);
  try {
    driver->motion()->Identify();
    FAIL() << "expected DeviceError";
  } catch (const DeviceError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("upper speed bound TU 12000"), std::string::npos) << what;
    EXPECT_EQ(what.find("PN/PX"), std::string::npos) << what;
  }
}

// A track's speed: PS in positions/s (the unit keeps it: a new session reads it back), and a
// speed beyond the unit's upper bound refused naming it.
TEST(FlirPtuEmulated, SetSpeedSendsPsAndRefusesASpeedBeyondTheBound) {
  EmulatedHead head("");
  {
    std::unique_ptr<DeviceDriver> driver = head.Open(EmulatedHead::Spec());
    driver->motion()->Identify();
    driver->motion()->SetSpeed(Axis::kPan, 20.0);  // 778 positions/s of 92.5714 arcsec
    EXPECT_NEAR(driver->motion()->Speed(Axis::kPan).speed, 778 * 92.5714 / 3600.0, 1e-6);
    try {
      driver->motion()->SetSpeed(Axis::kPan, 400.0);
      FAIL() << "expected DeviceError";
    } catch (const DeviceError& e) {
      EXPECT_NE(std::string(e.what()).find("upper speed bound PU 12000"), std::string::npos)
          << e.what();
    }
  }
  std::unique_ptr<DeviceDriver> again = head.Open(EmulatedHead::Spec());
  again->motion()->Identify();
  EXPECT_NEAR(again->motion()->Speed(Axis::kPan).speed, 778 * 92.5714 / 3600.0, 1e-6);
}

TEST(FlirPtu, ARefusedSpeedCommandGetsSpeedAdvice) {
  DeviceSpec spec = HeadSpec();
  spec.settings["speed_deg_s"] = {"30", 12};
  Head h(spec);
  h.wire->respond = [&h](const std::string& line) {
    if (line.rfind("TS", 0) == 0 && line.size() > 2) {
      return std::vector<std::string>{"! Maximum allowable Tilt speed exceeded"};
    }
    return h.ptu.Respond(line);
  };
  try {
    h.motion->Identify();
    FAIL() << "expected DeviceError";
  } catch (const DeviceError& e) {
    EXPECT_NE(std::string(e.what()).find("speed bounds"), std::string::npos) << e.what();
  }
}

TEST(FlirPtu, ValidateRejectsBadAxesAndUnknownKeys) {
  const DriverInfo* info = FindDriver("flir_ptu");
  EXPECT_NO_THROW(info->validate(HeadSpec()));
  DeviceSpec slide = HeadSpec();
  slide.axes[Axis::kSlide] = "pan";
  EXPECT_THROW(info->validate(slide), InputError);
  DeviceSpec twice = HeadSpec();
  twice.axes[Axis::kTilt] = "pan";
  EXPECT_THROW(info->validate(twice), InputError);
  DeviceSpec unknown = HeadSpec();
  unknown.settings["speed"] = {"3", 11};
  EXPECT_THROW(info->validate(unknown), InputError);
}

// Regression: reset_wait_s 1e308 overflowed to a negative count of milliseconds (undefined
// behaviour) and the PTU was declared absent at once; waits lie in (0, a day].
TEST(FlirPtu, ValidateRefusesWaitsBeyondADay) {
  const DriverInfo* info = FindDriver("flir_ptu");
  for (const char* key : {"reset_wait_s", "home_timeout_s"}) {
    for (const char* value : {"1e308", "86401", "0", "-5"}) {
      SCOPED_TRACE(std::string(key) + " " + value);
      DeviceSpec spec = HeadSpec();
      spec.settings[key] = {value, 12};
      try {
        info->validate(spec);
        ADD_FAILURE() << "accepted";
      } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("(0, 86400] s"), std::string::npos) << e.what();
      }
    }
  }
  DeviceSpec day = HeadSpec();
  day.settings["reset_wait_s"] = {"86400", 12};
  EXPECT_NO_THROW(info->validate(day));
  DeviceSpec tolerance = HeadSpec();  // cast to an integer count of positions later
  tolerance.settings["tolerance_positions"] = {"1e308", 12};
  EXPECT_THROW(info->validate(tolerance), InputError);
}

}  // namespace
}  // namespace irdist
