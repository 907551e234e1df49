// The flir_ptu driver's line kept in step and the unit's resets (station/flir_ptu_sync.cc),
// against a scripted PTU whose replies follow the FLIR PTU command reference's examples: terse
// feedback "* 22", a bare "*" for a command, "! ..." for an error, "!P" / "!T" when an axis hits a
// limit, the power-up banner ("Pan-Tilt Controller v3.2.0, ...") and "Initializing..." while the
// unit resets, during which it answers nothing. A (await) answers "*" once both axes have stopped.

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <deque>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "station/driver.h"
#include "station/transport.h"

namespace irdist {
namespace {

constexpr char kVersion[] = "Pan-Tilt Controller v3.2.0, (C)2010 FLIR Motion Control Systems, Inc.";

// A PTU with echo off, terse feedback, axes that reach their targets at once.
struct ScriptedPtu {
  long long pan = 0, tilt = 0;
  std::string version = kVersion;
  std::vector<std::string> commands;
  std::deque<std::string> lines;  // what the unit has sent and the driver has not read yet
  // The unit is resetting: it answers the next `silent_v` V's with this text (or nothing).
  int silent_v = 0;
  std::string chatter;
  bool never_confirm = false;  // A is never answered
  bool another_device = false;  // a Zaber stage on the port: every line gets its own reply

  std::string Answer(const std::string& c) {
    if (c == "V") return "* " + version;
    if (c == "ED" || c == "FT" || c == "I" || c == "H") return "*";
    if (c == "R") {
      pan = tilt = 0;
      return "*";
    }
    if (c == "A") return never_confirm ? "" : "*";
    if (c.size() < 2 || (c[0] != 'P' && c[0] != 'T')) return "! Illegal command";
    long long& pos = c[0] == 'P' ? pan : tilt;
    const std::string rest = c.substr(2);
    switch (c[1]) {
      case 'R': return "* 185.1428";
      case 'N': return "* -3090";
      case 'X': return "* 3090";
      case 'S': return rest.empty() ? "* 1000" : "*";
      case 'A': return rest.empty() ? "* 2000" : "*";
      case 'U': return "* 4000";
      case 'L': return "* 0";
      case 'P':
        if (rest.empty()) return "* " + std::to_string(pos);
        pos = std::stoll(rest);
        return "*";
    }
    return "! Illegal command";
  }
  void Receive(const std::string& c) {
    commands.push_back(c);
    if (another_device) {
      lines.push_back("@01 0 OK IDLE -- 0");
      return;
    }
    if (c == "V" && silent_v > 0) {
      --silent_v;
      if (!chatter.empty()) lines.push_back(chatter);
      return;
    }
    const std::string reply = Answer(c);
    if (!reply.empty()) lines.push_back(reply);
  }
  int Count(const std::string& c) const {
    return static_cast<int>(std::count(commands.begin(), commands.end(), c));
  }
};

// The serial line to the unit: an empty queue is a read timeout; lines already received are
// returned by ReadPending, as the serial transport does.
class ScriptedLine : public Transport {
 public:
  explicit ScriptedLine(std::shared_ptr<ScriptedPtu> ptu) : ptu_(std::move(ptu)) {}
  void WriteLine(std::string_view line) override { ptu_->Receive(std::string(line)); }
  std::string ReadLine(std::chrono::milliseconds) override {
    if (ptu_->lines.empty()) throw LinkError("no reply", "/dev/ttyUSB1", "test");
    std::string line = ptu_->lines.front();
    ptu_->lines.pop_front();
    return line;
  }
  void Flush() override { ptu_->lines.clear(); }
  std::vector<std::string> ReadPending() override {
    std::vector<std::string> pending(ptu_->lines.begin(), ptu_->lines.end());
    ptu_->lines.clear();
    return pending;
  }

 private:
  std::shared_ptr<ScriptedPtu> ptu_;
};

DeviceSpec HeadSpec() {
  DeviceSpec spec;
  spec.name = "head";
  spec.driver = "flir_ptu";
  spec.port = "/dev/ttyUSB1";
  spec.file = "rig.yaml";
  spec.line = 10;
  spec.axes[Axis::kPan] = "pan";
  spec.axes[Axis::kTilt] = "tilt";
  spec.settings["retries"] = {"2", 11};  // 3 attempts
  spec.settings["reset_wait_s"] = {"0.3", 12};
  return spec;
}

struct Head {
  std::shared_ptr<ScriptedPtu> ptu = std::make_shared<ScriptedPtu>();
  std::unique_ptr<DeviceDriver> driver;
  Motion* motion = nullptr;
  explicit Head(const DeviceSpec& spec = HeadSpec()) {
    driver = FindDriver("flir_ptu")->create(spec, std::make_unique<ScriptedLine>(ptu));
    motion = driver->motion();
  }
  // Identified, homed, and at pan 10 deg (194 positions of 185.1428 arc seconds).
  void Ready() {
    motion->Identify();
    motion->Home();
    StationPosition target;
    target.pan_deg = 10.0;
    motion->StartMove(target);
    motion->WaitSettled(std::chrono::milliseconds(5000));
  }
};

template <typename E, typename F>
std::string MessageOf(F f) {
  try {
    f();
  } catch (const E& e) {
    return e.what();
  }
  return "(nothing thrown)";
}

// A unit busy resetting ("Initializing...", no answer) for more V's than the attempts is waited
// for, up to reset_wait_s, and then identified.
TEST(FlirPtuSync, AResettingUnitIsWaitedForBeyondTheAttempts) {
  Head h;
  h.ptu->silent_v = 6;
  h.ptu->chatter = "Initializing...";
  EXPECT_EQ(h.motion->Identify().firmware, kVersion);
  EXPECT_GE(h.ptu->Count("V"), 7);
}

// Another device that answers, never as a PTU, is refused after the attempts (3 V's), naming
// what it said.
TEST(FlirPtuSync, ADeviceThatNeverAnswersAsAPtuIsRefusedAfterTheAttempts) {
  Head h;
  h.ptu->another_device = true;
  const std::string what = MessageOf<DeviceError>([&] { h.motion->Identify(); });
  EXPECT_NE(what.find("never with a pan-tilt unit's version"), std::string::npos) << what;
  EXPECT_NE(what.find("@01 0 OK IDLE"), std::string::npos) << what;
  EXPECT_EQ(h.ptu->Count("V"), 3);
  EXPECT_EQ(h.ptu->Count("R"), 0);
}

// A port where nothing answers at all: given up after reset_wait_s (300 ms), saying so.
TEST(FlirPtuSync, ASilentPortIsGivenUpAfterTheResetWait) {
  Head h;
  h.ptu->silent_v = 1000000;
  const auto start = std::chrono::steady_clock::now();
  const std::string what = MessageOf<DeviceError>([&] { h.motion->Identify(); });
  const double waited_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_NE(what.find("no answer to V within reset_wait_s (300 ms)"), std::string::npos) << what;
  EXPECT_GE(waited_s, 0.3);
  EXPECT_LT(waited_s, 1.5);
}

// The unit's own "!T" (tilt hit a limit), read before the next command: an error naming the axis,
// and the unit no longer counts as homed.
TEST(FlirPtuSync, TheUnitsLimitHitReportNamesTheAxis) {
  Head h;
  h.Ready();
  h.ptu->lines.push_back("!T");
  const std::string what = MessageOf<DeviceError>([&] { h.motion->CheckAlive(); });
  EXPECT_NE(what.find("tilt axis hit its limit"), std::string::npos) << what;
  EXPECT_EQ(h.motion->State(), MotionState::kUnhomed);
}

// The power-up banner read between commands while homed: the unit was reset (a restart), and
// homing identifies it again before it resets the axes.
TEST(FlirPtuSync, APowerUpBannerWhileHomedIsARestartAndHomingIdentifiesAgain) {
  Head h;
  h.Ready();
  h.ptu->lines.push_back("Initializing...");
  EXPECT_THROW(h.motion->CheckAlive(), DeviceRestarted);
  EXPECT_EQ(h.motion->State(), MotionState::kUnhomed);
  const int ed_before = h.ptu->Count("ED");
  h.motion->Home();
  EXPECT_EQ(h.ptu->Count("ED"), ed_before + 1) << "not identified again after the restart";
  EXPECT_EQ(h.motion->State(), MotionState::kIdle);
}

// After a restart, a unit whose version is not the one found at connection is another unit: it
// is refused as that (not as "never a pan-tilt unit"), quoting what it answered, and never reset.
TEST(FlirPtuSync, AnotherUnitFoundAfterARestartIsRefused) {
  Head h;
  h.Ready();
  h.ptu->lines.push_back("Initializing...");
  EXPECT_THROW(h.motion->CheckAlive(), DeviceRestarted);
  h.ptu->version = "Pan-Tilt Controller v3.4.1, (C)2014 FLIR Motion Control Systems, Inc.";
  const std::string what = MessageOf<DeviceError>([&] { h.motion->Home(); });
  EXPECT_NE(what.find("v3.4.1"), std::string::npos) << what;
  EXPECT_NE(what.find("not with the version identified at connection"), std::string::npos) << what;
  EXPECT_NE(what.find("the one the run started with"), std::string::npos) << what;
  EXPECT_EQ(h.ptu->Count("R"), 1) << "the other unit was reset";
  EXPECT_EQ(h.motion->State(), MotionState::kUnhomed);
}

// No move ends before the unit confirms it (A); a unit that never does is a LinkError after the
// attempts, naming the device and the port.
TEST(FlirPtuSync, AMoveTheUnitNeverConfirmsIsALinkError) {
  Head h;
  h.Ready();
  EXPECT_GE(h.ptu->Count("A"), 1);
  h.ptu->never_confirm = true;
  StationPosition target;
  target.pan_deg = 20.0;
  h.motion->StartMove(target);
  const std::string what =
      MessageOf<LinkError>([&] { h.motion->WaitSettled(std::chrono::milliseconds(5000)); });
  EXPECT_NE(what.find("never confirmed the end of its moves (A, await: 3 attempts"),
            std::string::npos)
      << what;
  EXPECT_NE(what.find("flir_ptu 'head'"), std::string::npos) << what;
  EXPECT_NE(what.find("/dev/ttyUSB1"), std::string::npos) << what;
}

// At rest, an axis found away from its target: the unit restarted (its reset moved the axes).
TEST(FlirPtuSync, AnAxisAwayFromItsTargetAtRestIsARestart) {
  Head h;
  h.Ready();
  EXPECT_NO_THROW(h.motion->CheckAlive());
  h.ptu->pan = 0;
  const std::string what = MessageOf<DeviceRestarted>([&] { h.motion->CheckAlive(); });
  EXPECT_NE(what.find("pan at 0 instead of 194"), std::string::npos) << what;
  EXPECT_EQ(h.motion->State(), MotionState::kUnhomed);
}

}  // namespace
}  // namespace irdist
