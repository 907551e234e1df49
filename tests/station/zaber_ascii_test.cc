// The zaber_ascii driver against a scripted Zaber device (replies shaped as the ASCII Protocol
// Manual's examples: "@01 1 12 OK IDLE -- 0").

#include <gtest/gtest.h>

#include <cstdio>
#include <sstream>

#include "base/input_error.h"
#include "sim/device_emulator.h"
#include "sim/line_device.h"
#include "sim/world.h"
#include "station/driver.h"
#include "station/serial_transport.h"
#include "tests/station/fake_transport.h"
#include "tests/station/rig_fixture.h"

namespace irdist {
namespace {

std::string Lrc(const std::string& body) {
  unsigned sum = 0;
  for (unsigned char c : body) sum += c;
  char hex[3];
  std::snprintf(hex, sizeof(hex), "%02X", (256u - (sum & 0xFFu)) & 0xFFu);
  return hex;
}

// A one-axis Zaber stage: device 1, axis 1.
struct Stage {
  long long pos = 0, target = 0;
  int busy_polls = 0;     // `get pos` polls still answering BUSY
  bool referenced = false;
  std::string warning = "--";
  long long limit_max = 4199475;  // ~200 mm at 0.047625 um
  int drop_next = 0;      // replies to drop
  int garble_next = 0;    // replies to corrupt
  bool reject_moves = false;
  bool stall = false;     // moves end short of the target
  std::vector<std::string> commands;

  std::string Data(const std::string& cmd) {
    if (cmd == "get deviceid") return "50081";
    if (cmd == "get system.serial") return "12345";
    if (cmd == "get version") return "7.25";
    if (cmd == "get resolution") return "64";
    if (cmd == "get limit.min") return "0";
    if (cmd == "get limit.max") return std::to_string(limit_max);
    if (cmd == "get maxspeed") return "153600";
    if (cmd == "get accel") return "205";
    return "0";
  }

  std::vector<std::string> Respond(const std::string& line) {
    std::string body = line.substr(1);
    const std::size_t colon = body.rfind(':');
    EXPECT_NE(colon, std::string::npos) << line;
    EXPECT_EQ(body.substr(colon + 1), Lrc(body.substr(0, colon))) << line;
    body.resize(colon);
    std::istringstream in(body);
    int device = 0, axis = 0, id = 0;
    in >> device >> axis >> id;
    std::string cmd;
    std::getline(in >> std::ws, cmd);
    commands.push_back(cmd);
    std::string flag = "OK", data = Data(cmd);
    if (cmd == "home") {
      referenced = true;
      target = 0;
      busy_polls = 2;
      warning = "--";
    } else if (cmd.rfind("move abs ", 0) == 0) {
      const long long t = std::stoll(cmd.substr(9));
      if (reject_moves || t > limit_max) {
        flag = "RJ";
        data = "BADDATA";
      } else {
        target = t;
        busy_polls = 3;
      }
    } else if (cmd == "warnings clear") {
      warning = "--";
    } else if (cmd == "stop") {
      busy_polls = 0;
      target = pos;
    } else if (cmd == "get pos") {
      if (busy_polls > 0) --busy_polls;
      if (busy_polls == 0) pos = stall ? target / 2 : target;
      data = std::to_string(pos);
    }
    const std::string status = busy_polls > 0 ? "BUSY" : "IDLE";
    const std::string flags = referenced ? warning : "WR";
    std::string reply = "01 " + std::to_string(axis) + " " + std::to_string(id) + " " + flag +
                        " " + status + " " + flags + " " + data;
    reply = "@" + reply + ":" + Lrc(reply);
    if (drop_next > 0) {
      --drop_next;
      return {};
    }
    if (garble_next > 0) {
      --garble_next;
      reply[5] = reply[5] == '9' ? '8' : '9';  // the id changes, the checksum no longer matches
    }
    return {reply};
  }
  // A power cycle: the stage keeps its position counter at 0 and has no reference.
  void PowerCycle() {
    referenced = false;
    pos = target = 0;
    busy_polls = 0;
  }
};

DeviceSpec SlideSpec() {
  DeviceSpec spec = FakeDeviceSpec("slide", "zaber_ascii", "/dev/ttyUSB0", 3);
  spec.axes[Axis::kSlide] = "1 1";
  spec.settings["fullstep_um"] = {"3.048", 5};
  spec.settings["origin_mm"] = {"1000", 6};
  spec.settings["retries"] = {"2", 7};
  return spec;
}

struct Rig : FakeDeviceBench<Stage> {
  Stage& stage = device;
  Motion* motion = driver->motion();
  explicit Rig(const DeviceSpec& spec = SlideSpec()) : FakeDeviceBench("zaber_ascii", spec) {}
  int Count(const std::string& prefix) const {
    int n = 0;
    for (const std::string& c : stage.commands) n += c.rfind(prefix, 0) == 0;
    return n;
  }
};

TEST(ZaberAscii, RegistersAsMotionDriver) {
  const DriverInfo* info = FindDriver("zaber_ascii");
  ASSERT_NE(info, nullptr);
  EXPECT_EQ(info->roles, std::vector<std::string>{"motion"});
  EXPECT_EQ(info->line_end, "\n");
  EXPECT_EQ(info->default_baud, 115200u);
}

TEST(ZaberAscii, IdentifyReadsIdentityUnitsAndSpeed) {
  Rig rig;
  const DeviceIdentity id = rig.motion->Identify();
  EXPECT_EQ(id.vendor, "Zaber");
  EXPECT_EQ(id.model, "deviceid 50081");
  EXPECT_EQ(id.serial, "12345");
  EXPECT_EQ(id.firmware, "7.25");
  EXPECT_EQ(id.port, "/dev/ttyUSB0");
  const AxisSpeed speed = rig.motion->Speed(Axis::kSlide);
  // 153600 / 1.6384 = 93750 microsteps/s of 3.048/64 um.
  EXPECT_NEAR(speed.speed, 93750 * 3.048e-3 / 64, 1e-9);
  // 205 x 10000 / 1.6384 = 1251221 microsteps/s^2.
  EXPECT_NEAR(speed.acceleration, 205 * 10000 / 1.6384 * 3.048e-3 / 64, 1e-6);
  EXPECT_DOUBLE_EQ(speed.home, 1000.0);
  EXPECT_EQ(rig.motion->Axes(), std::vector<Axis>{Axis::kSlide});
}

TEST(ZaberAscii, WrongDeviceOnThePortIsADeviceErrorBeforeAnythingMoves) {
  Rig rig;
  rig.wire->respond = [](const std::string&) {
    return std::vector<std::string>{"* Pan-Tilt Controller v3.2"};
  };
  try {
    rig.motion->Identify();
    FAIL() << "expected DeviceError";
  } catch (const DeviceError& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/ttyUSB0"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("Pan-Tilt"), std::string::npos) << e.what();
  }
  for (const std::string& line : rig.wire->written) {
    EXPECT_EQ(line.find("move"), std::string::npos);
    EXPECT_EQ(line.find("home"), std::string::npos);
  }
}

TEST(ZaberAscii, ExpectedDeviceidMismatchIsADeviceError) {
  DeviceSpec spec = SlideSpec();
  spec.settings["deviceid"] = {"30221", 8};
  Rig rig(spec);
  EXPECT_THROW(rig.motion->Identify(), DeviceError);
}

TEST(ZaberAscii, HomesThenMovesInMillimetres) {
  Rig rig;
  rig.motion->Identify();
  EXPECT_EQ(rig.motion->State(), MotionState::kUnhomed);
  rig.motion->Home();
  EXPECT_EQ(rig.Count("home"), 1);
  StationPosition target;
  target.slide_mm = 1100.0;
  rig.motion->StartMove(target);
  // 100 mm / 0.047625 um = 2099738 microsteps.
  EXPECT_EQ(rig.stage.commands.back(), "move abs 2099738");
  rig.motion->WaitSettled(std::chrono::milliseconds(5000));
  StationPosition now;
  rig.motion->ReadPosition(&now);
  EXPECT_NEAR(now.slide_mm, 1100.0, 1e-4);
  EXPECT_EQ(rig.motion->State(), MotionState::kIdle);
}

TEST(ZaberAscii, DirectionMinusOneMirrorsTheAxis) {
  DeviceSpec spec = SlideSpec();
  spec.settings["direction"] = {"-1", 9};
  spec.settings["origin_mm"] = {"1200", 6};
  Rig rig(spec);
  rig.motion->Identify();
  rig.motion->Home();
  StationPosition target;
  target.slide_mm = 1100.0;
  rig.motion->StartMove(target);
  EXPECT_EQ(rig.stage.commands.back(), "move abs 2099738");
}

TEST(ZaberAscii, TargetOutsideTheTravelIsRefusedBeforeSending) {
  Rig rig;
  rig.motion->Identify();
  rig.motion->Home();
  StationPosition target;
  target.slide_mm = 1300.0;  // 300 mm on a 200 mm stage
  EXPECT_THROW(rig.motion->StartMove(target), DeviceError);
  EXPECT_EQ(rig.Count("move abs"), 0);
}

TEST(ZaberAscii, RejectedMoveIsADeviceErrorWithTheReason) {
  Rig rig;
  rig.motion->Identify();
  rig.motion->Home();
  rig.stage.reject_moves = true;
  StationPosition target;
  target.slide_mm = 1050.0;
  try {
    rig.motion->StartMove(target);
    FAIL() << "expected DeviceError";
  } catch (const DeviceError& e) {
    EXPECT_EQ(e.device_code(), "RJ BADDATA");
  }
}

TEST(ZaberAscii, GarbledAndDroppedQueryRepliesAreRetried) {
  Rig rig;
  rig.motion->Identify();
  rig.stage.garble_next = 1;
  rig.stage.drop_next = 1;
  StationPosition now;
  rig.motion->ReadPosition(&now);  // third attempt answers
  EXPECT_NEAR(now.slide_mm, 1000.0, 1e-9);
  EXPECT_EQ(rig.Count("get pos"), 3);
}

TEST(ZaberAscii, ReplyWhoseChecksumWasDamagedAwayIsNotTaken) {
  Rig rig;
  rig.motion->Identify();
  int damaged = 1;
  rig.wire->respond = [&rig, &damaged](const std::string& line) {
    std::vector<std::string> replies = rig.stage.Respond(line);
    if (damaged > 0 && !replies.empty()) {
      --damaged;
      std::string& r = replies.front();
      r = r.substr(0, r.rfind(':')) + "7";  // ':' garbled: "...-- 0" -> "...-- 07"
    }
    return replies;
  };
  StationPosition now;
  rig.motion->ReadPosition(&now);
  EXPECT_NEAR(now.slide_mm, 1000.0, 1e-9);
  EXPECT_EQ(rig.Count("get pos"), 2);
}

// The LinkError's message when an identified device's every reply is dropped (`drop`) or garbled
// while its position is read, reset_wait_s 50 ms ("" when none came); *asked: the queries sent.
std::string LinkErrorReadingPosition(bool drop, int* asked) {
  DeviceSpec spec = SlideSpec();
  spec.settings["reset_wait_s"] = {"0.05", 8};
  Rig rig(spec);
  rig.motion->Identify();
  (drop ? rig.stage.drop_next : rig.stage.garble_next) = 1 << 30;
  StationPosition now;
  std::string what;
  try {
    rig.motion->ReadPosition(&now);
  } catch (const LinkError& e) {
    what = e.what();
  }
  *asked = rig.Count("get pos");
  return what;
}

// Identified, a device silent through every retry may be booting after a power cut: asked again
// up to reset_wait_s, then a LinkError naming the wait and the device, by its address and by the
// rig file's protocol (the user finds it among the rig's). Replies garbled every time the same.
TEST(ZaberAscii, SilentDeviceIsALinkErrorAfterResetWait) {
  for (const bool drop : {true, false}) {
    int asked = 0;
    const std::string what = LinkErrorReadingPosition(drop, &asked);
    EXPECT_NE(what.find("silent for reset_wait_s (50 ms)"), std::string::npos) << what;
    EXPECT_NE(what.find("Zaber device 1 (zaber_ascii)"), std::string::npos) << what;
    EXPECT_GT(asked, 3);  // 1 + retries, then asked again through the wait
  }
}

TEST(ZaberAscii, LostMoveReplyIsNotResentWhenTheStageStarted) {
  Rig rig;
  rig.motion->Identify();
  rig.motion->Home();
  rig.stage.drop_next = 1;
  StationPosition target;
  target.slide_mm = 1010.0;
  rig.motion->StartMove(target);
  rig.motion->WaitSettled(std::chrono::milliseconds(5000));
  EXPECT_EQ(rig.Count("move abs"), 1);
}

TEST(ZaberAscii, StalledAxisStopsShortIsADeviceError) {
  Rig rig;
  rig.motion->Identify();
  rig.motion->Home();
  rig.stage.stall = true;
  StationPosition target;
  target.slide_mm = 1010.0;
  rig.motion->StartMove(target);
  EXPECT_THROW(rig.motion->WaitSettled(std::chrono::milliseconds(5000)), DeviceError);
}

TEST(ZaberAscii, FaultFlagIsADeviceErrorNamingTheFlag) {
  Rig rig;
  rig.motion->Identify();
  rig.motion->Home();
  rig.stage.warning = "FS";
  try {
    rig.motion->CheckAlive();
    FAIL() << "expected DeviceError";
  } catch (const DeviceError& e) {
    EXPECT_EQ(e.device_code(), "FS");
    EXPECT_NE(std::string(e.what()).find("stalled"), std::string::npos) << e.what();
  }
  EXPECT_EQ(rig.motion->State(), MotionState::kFault);
}

TEST(ZaberAscii, LostReferenceAfterHomingIsARestart) {
  Rig rig;
  rig.motion->Identify();
  rig.motion->Home();
  rig.motion->CheckAlive();
  rig.stage.PowerCycle();
  EXPECT_THROW(rig.motion->CheckAlive(), DeviceRestarted);
  EXPECT_EQ(rig.motion->State(), MotionState::kUnhomed);
  rig.motion->Home();  // homing again recovers
  rig.motion->CheckAlive();
}

TEST(ZaberAscii, ValidateRejectsUnknownKeysAndMissingStepSize) {
  const DriverInfo* info = FindDriver("zaber_ascii");
  ASSERT_NE(info, nullptr);
  EXPECT_NO_THROW(info->validate(SlideSpec()));
  DeviceSpec unknown = SlideSpec();
  unknown.settings["origin"] = {"1000", 12};
  try {
    info->validate(unknown);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.Line(), 12);
  }
  DeviceSpec no_step = SlideSpec();
  no_step.settings.erase("fullstep_um");
  EXPECT_THROW(info->validate(no_step), InputError);
  DeviceSpec bad_address = SlideSpec();
  bad_address.axes[Axis::kSlide] = "1 x";
  EXPECT_THROW(info->validate(bad_address), InputError);
  DeviceSpec bad_direction = SlideSpec();
  bad_direction.settings["direction"] = {"2", 4};
  EXPECT_THROW(info->validate(bad_direction), InputError);
  // Cast to integers later: 1e308 would be undefined behaviour (base/bounds.h).
  for (const char* key : {"tolerance_microsteps", "home_timeout_s"}) {
    SCOPED_TRACE(key);
    DeviceSpec huge = SlideSpec();
    huge.settings[key] = {"1e308", 5};
    try {
      info->validate(huge);
      ADD_FAILURE() << "accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(std::string(key) + " = 1e+308 is outside"),
                std::string::npos)
          << e.what();
    }
  }
}

// --- Against the Zaber emulator (sim/zaber_emulator.cc, written from the manual) over a pty.

std::string EmulatedRig(const std::string& virtual_extra) {
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
         "      microstep_um: 0.09921875\n"
         "      accel_mm_s2: 1000\n" +  // `get accel` = 1651
         virtual_extra;
}

struct EmulatedSlide {
  explicit EmulatedSlide(const std::string& virtual_extra)
      : emulator(sim::FindEmulator("zaber_ascii")->create(
            world, {"slide", "zaber_ascii", "inline.yaml", EmulatedRig(virtual_extra), 1})) {
    port = emulator->Start();
  }
  std::unique_ptr<DeviceDriver> Open(DeviceSpec spec) {
    const DriverInfo* info = FindDriver("zaber_ascii");
    SerialOptions serial;
    serial.line_end = info->line_end;
    spec.port = port;
    spec.reply_timeout_ms = 100;
    return info->create(spec, std::make_unique<SerialTransport>(port, serial));
  }
  sim::World world{20.0};
  std::unique_ptr<sim::DeviceEmulator> emulator;
  std::string port;
};

// One flipped bit in `get accel` at connection ("1651" -> "16=1"), on a device that does not
// checksum its replies: asked again, the connection completes.
TEST(ZaberAsciiEmulated, ADamagedReplyAtConnectionIsAskedAgain) {
  EmulatedSlide slide("      flip_reply: get accel\n      flip_byte: -2\n      flip_bit: 3\n");
  DeviceSpec spec = SlideSpec();
  spec.settings["checksum"] = {"false", 8};
  std::unique_ptr<DeviceDriver> driver = slide.Open(spec);
  EXPECT_NO_THROW(driver->motion()->Identify());
  // 1651 acceleration data at the rig file's 3.048 um / 64 microstep.
  EXPECT_NEAR(driver->motion()->Speed(Axis::kSlide).acceleration,
              1651 / 1.6384e-4 * 3.048e-3 / 64, 1e-6);
}

// A track's speed: `set maxspeed` in the manual's data units (microsteps/s x 1.6384); the device
// keeps it (a new session reads it back with `get maxspeed`).
TEST(ZaberAsciiEmulated, SetSpeedSetsTheDevicesMaxspeed) {
  EmulatedSlide slide("");
  {
    std::unique_ptr<DeviceDriver> driver = slide.Open(SlideSpec());
    driver->motion()->Identify();
    driver->motion()->SetSpeed(Axis::kSlide, 50.0);
    EXPECT_NEAR(driver->motion()->Speed(Axis::kSlide).speed, 50.0, 1e-3);
  }
  std::unique_ptr<DeviceDriver> again = slide.Open(SlideSpec());
  again->motion()->Identify();
  EXPECT_NEAR(again->motion()->Speed(Axis::kSlide).speed, 50.0, 1e-3);
}

// A reply damaged in every attempt is a link problem, never "map one axis per address".
TEST(ZaberAsciiEmulated, ARepliesDamagedEveryTimeGetLinkAdvice) {
  EmulatedSlide slide("      flip_reply: get accel\n      flip_byte: -2\n      flip_bit: 3\n"
                      "      flip_count: 100\n");
  DeviceSpec spec = SlideSpec();
  spec.settings["checksum"] = {"false", 8};
  std::unique_ptr<DeviceDriver> driver = slide.Open(spec);
  try {
    driver->motion()->Identify();
    FAIL() << "expected an error";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.find("map one axis"), std::string::npos) << what;
    EXPECT_NE(what.find("get accel"), std::string::npos) << what;
    EXPECT_NE(what.find("cable"), std::string::npos) << what;
  }
}

// Manual, comm.checksum: the driver makes the device checksum its replies; a position with one
// flipped bit then fails its checksum and is asked again, never taken.
TEST(ZaberAsciiEmulated, RepliesAreChecksummedAndADamagedPositionIsNeverTaken) {
  EmulatedSlide slide("");
  std::unique_ptr<DeviceDriver> driver = slide.Open(SlideSpec());
  driver->motion()->Identify();
  driver->motion()->Home();
  StationPosition target;
  target.slide_mm = 1500.0;  // 10498688 microsteps
  driver->motion()->StartMove(target);
  driver->motion()->WaitSettled(std::chrono::milliseconds(20000));
  StationPosition at;
  driver->motion()->ReadPosition(&at);
  // Bit 0 of the byte 6 from the end: a digit of the position with or without ":CC" after it
  // ("10498688:CC" -> "10498788:CC"), in the next two replies to `get pos`.
  dynamic_cast<sim::LineDevice&>(*slide.emulator).SetReplyBitFlip({"get pos", -6, 0, 2});
  StationPosition p;
  for (int i = 0; i < 3; ++i) {
    driver->motion()->ReadPosition(&p);
    EXPECT_DOUBLE_EQ(p.slide_mm, at.slide_mm);
  }
  EXPECT_EQ(dynamic_cast<sim::LineDevice&>(*slide.emulator).RepliesFlipped(), 2u);
}

// Regression: no move ends (and so no frame is exposed) before the stage itself says it is
// idle: with replies dropped and delayed past the reply timeout, every move returns with the
// stage at rest at its target; a late reply (its message id an earlier one's) is never taken.
TEST(ZaberAsciiEmulated, NoMoveEndsBeforeTheStageConfirmsIt) {
  EmulatedSlide slide("");
  DeviceSpec spec = SlideSpec();
  spec.settings["retries"] = {"8", 9};
  std::unique_ptr<DeviceDriver> driver = slide.Open(spec);
  Motion& motion = testing::IdentifiedAndHomed(*driver);
  // 4 simulated seconds: 0.2 s at the bench's time scale, twice the reply timeout.
  slide.emulator->SetFaults(testing::LossyReplies(4.0));
  for (int i = 0; i < 8; ++i) {
    StationPosition target;
    target.slide_mm = 1200.0 + 37.5 * i;
    motion.StartMove(target);
    motion.WaitSettled(std::chrono::milliseconds(60000));
    EXPECT_FALSE(slide.world.Pose().moving) << "move " << i << " ended while still moving";
    StationPosition at;
    motion.ReadPosition(&at);
    EXPECT_NEAR(at.slide_mm, target.slide_mm, 0.01) << "move " << i;
  }
}

// The slide's driver, waiting up to `reset_wait_s` for a silent device (a boot after a power cut).
std::unique_ptr<DeviceDriver> OpenWaiting(EmulatedSlide& slide, const std::string& reset_wait_s) {
  DeviceSpec spec = SlideSpec();
  spec.settings["reset_wait_s"] = {reset_wait_s, 9};
  return slide.Open(spec);
}

// After a restart: homed (and so identified) again, the retaken move lands at rest.
void HomeAgainAndLand(EmulatedSlide& slide, Motion& motion, double slide_mm) {
  motion.Home();
  StationPosition target;
  target.slide_mm = slide_mm;
  motion.StartMove(target);
  motion.WaitSettled(std::chrono::milliseconds(20000));
  EXPECT_FALSE(slide.world.Pose().moving);
  StationPosition at;
  motion.ReadPosition(&at);
  EXPECT_NEAR(at.slide_mm, slide_mm, 0.01);
}

// Regression: a power cut whose boot outlasts every retry (30 simulated s, 1.5 s here; the
// driver gives up on a silent query after 5 x 100 ms) is waited out up to reset_wait_s: at rest,
// the device answers again with its reference lost (WR), a restart; the next Home identifies the
// device again and the retaken move lands.
TEST(ZaberAsciiEmulated, ASilentPowerCutAtRestIsWaitedOutIdentifiedAndHomedAgain) {
  EmulatedSlide slide("      reset_s: 30\n");
  std::unique_ptr<DeviceDriver> driver = OpenWaiting(slide, "20");
  Motion& motion = testing::IdentifiedAndHomed(*driver);
  slide.emulator->PowerCycle();
  EXPECT_THROW(motion.CheckAlive(), DeviceRestarted);
  HomeAgainAndLand(slide, motion, 1750.0);
}

// The same power cut in the middle of a move, the controller sending an alert ("!01 0 IDLE WR")
// when it is up: the wait for the move sees the boot through, passes the alert over and reports
// the restart (never a settled move); homed again, the retaken move lands.
TEST(ZaberAsciiEmulated, APowerCutMidMoveThatAlertsIsARestartOnceTheBootEnds) {
  EmulatedSlide slide("      reset_s: 30\n      power_up_alert: true\n");
  std::unique_ptr<DeviceDriver> driver = OpenWaiting(slide, "20");
  Motion& motion = testing::IdentifiedAndHomed(*driver);
  StationPosition target;
  target.slide_mm = 2100.0;
  motion.StartMove(target);
  slide.emulator->PowerCycle();
  EXPECT_THROW(motion.WaitSettled(std::chrono::milliseconds(20000)), DeviceRestarted);
  HomeAgainAndLand(slide, motion, 2100.0);
}

// A device silent for longer than reset_wait_s is gone: a LinkError naming the wait.
TEST(ZaberAsciiEmulated, ABootLongerThanResetWaitIsALinkErrorNamingIt) {
  EmulatedSlide slide("      reset_s: 200\n");
  std::unique_ptr<DeviceDriver> driver = OpenWaiting(slide, "1");
  Motion& motion = testing::IdentifiedAndHomed(*driver);
  slide.emulator->PowerCycle();
  try {
    motion.CheckAlive();
    FAIL() << "expected a LinkError";
  } catch (const DeviceRestarted& e) {
    FAIL() << "a restart before the device answered: " << e.what();
  } catch (const LinkError& e) {
    EXPECT_NE(std::string(e.what()).find("reset_wait_s"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace irdist
