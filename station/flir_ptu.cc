// The FLIR (formerly Directed Perception) PTU driver (docs/devices/flir_ptu.md): a PTU-E series
// pan-tilt unit as the motion role for pan and tilt. Written from the "Pan-Tilt Unit (E Series)
// Command Reference Manual" and the PTU-D46 user's manual's command reference: commands end with
// a delimiter (CR, [ENTER]), replies start with '*' (done) or '!' (error); positions are integers in
// the unit's native steps, whose size PR/TR report in seconds of arc.
//
// The protocol has no request ids: replies are matched by order, one per command. Echo is
// switched off (ED) and feedback set terse (FT) at connection; the parser still takes the text
// after the first '*' or '!' so an echoed command or verbose feedback parses the same. The class
// is declared in station/flir_ptu_driver.h; the line kept in step and the unit's resets are in
// station/flir_ptu_sync.cc.

#include <sstream>
#include <thread>

#include "base/bounds.h"
#include "station/flir_ptu_driver.h"
#include "station/serial_driver.h"

namespace irdist::flir_ptu_internal {

LineQueryOptions FlirPtu::QueryOptions(const DeviceSpec& spec) {
  LineQueryOptions options =
      QueryOptionsOf(spec, 4, 1000, "the PTU",
                     "check the cable, the baud rate (PTU default 9600) and power");
  // Replies carry no id: whatever arrived before a command (a late reply to an earlier one) is
  // not its reply, but a limit-hit report among it is seen. After a lost reply the unit may be
  // resetting (it answers nothing until done, then every command queued meanwhile): the stream
  // is resynchronised on the answer to V before anything is sent again.
  options.before_send = [this](int attempt) {
    TakePending(true);
    if (attempt > 0 || out_of_step_) SyncOnVersion();
    NotePowerUp();
  };
  options.after_miss = [this] { out_of_step_ = true; };
  return options;
}

// A command's reply: the text after '*' (into *body). A line with neither '*' nor '!' (a banner,
// a bare echo, noise) is passed over. A '!' reply is a DeviceError carrying the unit's message.
ReplyVerdict FlirPtu::Judge(const std::string& command, const std::string& line,
                            std::string* body) const {
  const std::size_t mark = line.find_first_of("*!");
  if (mark == std::string::npos) {
    NotePowerUpText(line);
    return ReplyVerdict::kSkip;
  }
  std::string text = line.substr(mark + 1);
  text.erase(0, text.find_first_not_of(' '));
  if (line[mark] == '*') {
    *body = text;
    return ReplyVerdict::kMatch;
  }
  if (IsLimitHit(line)) LimitHit(line);
  Fail("!" + text, "refused '" + command + "': " + text,
       IsRateCommand(command)
           ? "check the speed against the unit's speed bounds (PU/PL, TU/TL; `irdist station "
             "status` shows them) and lower speed_deg_s or accel_deg_s2 in the rig file"
           : "check the command's value against the unit's position limits (PN/PX/TN/TX)");
}

LineRequest FlirPtu::Request(const std::string& command, std::string* body) const {
  LineRequest request;
  request.query = command;
  request.judge = [this, command, body](const std::string& line) {
    return Judge(command, line, body);
  };
  return request;
}

// A query (changes nothing): retried after a lost or garbled reply.
std::string FlirPtu::Query(const std::string& command) {
  std::string body;
  query_.Ask(Request(command, &body));
  return body;
}

double FlirPtu::QueryNumber(const std::string& command) {
  std::string heard;
  for (int attempt = 0; attempt < attempts_; ++attempt) {
    const std::string body = Query(command);
    double value = 0;
    if (FirstNumber(body, &value)) return value;
    heard = "* " + body;
    TakePending(true);
  }
  Fail(heard, "'" + command + "' did not answer a number",
       "check that the unit is a PTU and in terse or verbose feedback mode");
}

// A command that changes state: sent once. False when its acknowledgement was lost.
bool FlirPtu::Command(const std::string& command, milliseconds wait) {
  std::string body;
  return query_.AskOnce(Request(command, &body), wait).has_value();
}

// The protocol has no checksum: a reported position is the same value read twice in a row.
long long FlirPtu::StablePosition(const PtuAxis& a) {
  long long last = Position(a);
  for (int attempt = 0; attempt < attempts_; ++attempt) {
    const long long now = Position(a);
    if (now == last) return now;
    last = now;
  }
  Fail("", AxisText(a) + " position does not read the same twice",
       "the axis is moving or the link is damaged; check the cable");
}

void FlirPtu::ReadAxis(PtuAxis* a) {
  const std::string p(1, a->letter);
  a->deg_per_position = QueryNumber(p + "R") / kArcsecPerDeg;
  if (!(a->deg_per_position > 0)) {
    Fail(p + "R", AxisText(*a) + " resolution is not positive", "check the unit");
  }
  a->min_pos = std::llround(QueryNumber(p + "N"));
  a->max_pos = std::llround(QueryNumber(p + "X"));
  a->speed_pos_s = std::llround(QueryNumber(p + "S"));
  a->speed.speed = static_cast<double>(a->speed_pos_s) * a->deg_per_position;
  a->speed.acceleration = QueryNumber(p + "A") * a->deg_per_position;
  a->speed.settle_ms = spec_.Number("settle_ms", 0.0);
  a->speed.home = 0.0;
  ReadSpeedBounds(a);
}

// PU / PL (TU / TL): the speeds PS (TS) may take. A unit that does not know them (a refusal)
// leaves them unchecked here; it refuses an out-of-range speed itself.
void FlirPtu::ReadSpeedBounds(PtuAxis* a) {
  const std::string p(1, a->letter);
  try {
    a->upper_pos_s = std::llround(QueryNumber(p + "U"));
    a->lower_pos_s = std::llround(QueryNumber(p + "L"));
  } catch (const DeviceError&) {
    a->upper_pos_s = a->lower_pos_s = 0;
  }
}

// Rig-file speed and acceleration, in positions per second (and per second squared).
void FlirPtu::ApplySpeed(PtuAxis* a) {
  const std::string p(1, a->letter);
  if (spec_.settings.count("speed_deg_s")) {
    SendSpeed(a, spec_.Number("speed_deg_s", 0),
              "set station.devices." + spec_.name + ".speed_deg_s within the unit's speed bounds");
  }
  if (spec_.settings.count("accel_deg_s2")) {
    const long long s = std::llround(spec_.Number("accel_deg_s2", 0) / a->deg_per_position);
    if (!Command(p + "A" + std::to_string(s), timeout_)) {
      LinkFail("no reply to " + p + "A", "check the cable");
    }
  }
}

// Manual, "Speed (absolute)": PS<positions/sec> (TS for tilt) sets the desired speed, changeable
// on the fly; a speed outside the bounds PU/PL (TU/TL) is refused by the unit, and checked here
// first where the bounds were read.
void FlirPtu::SendSpeed(PtuAxis* a, double deg_s, const std::string& fix) {
  const std::string p(1, a->letter);
  const long long s = std::llround(deg_s / a->deg_per_position);
  const bool above = a->upper_pos_s > 0 && s > a->upper_pos_s;
  if (above || s < a->lower_pos_s || s < 1) {
    const long long bound = above ? a->upper_pos_s : std::max(a->lower_pos_s, 1LL);
    Fail(p + (above ? "U " : "L ") + std::to_string(bound),
         "speed " + std::to_string(deg_s) + " deg/s is " + (above ? "above" : "below") + " the " +
             AxisText(*a) + " axis's " + (above ? "upper" : "lower") + " speed bound " + p +
             (above ? "U " : "L ") + std::to_string(bound) + " positions/s (" +
             std::to_string(bound * a->deg_per_position) + " deg/s)",
         fix);
  }
  if (!Command(p + "S" + std::to_string(s), timeout_)) {
    LinkFail("no reply to " + p + "S", "check the cable");
  }
  a->speed_pos_s = s;
  a->speed.speed = static_cast<double>(s) * a->deg_per_position;
}

void FlirPtu::SetSpeed(Axis axis, double unit_per_s) {
  for (PtuAxis& a : axes_) {
    if (a.axis == axis) SendSpeed(&a, unit_per_s, "ask for a speed within the unit's bounds");
  }
}

DeviceIdentity FlirPtu::Identify() {
  std::string version;
  homed_ = false;
  version_.clear();
  try {
    SyncOnVersion();  // stale replies (a reset, an earlier session) are read away first
    Query("ED");      // echo off; the reply may still carry the echo of "ED"
    Query("FT");      // terse feedback
    version = Query("V");
  } catch (const LinkError& e) {
    Fail("", std::string("no PTU answers on this port: ") + e.what(),
         "check that the port is the PTU's (ls -l /dev/serial/by-id) and its baud rate");
  }
  if (!ptu_text::NamesAPanTiltUnit(version)) {
    Fail(version, "the device on this port answered V with '" + version + "', not a pan-tilt "
                  "unit's version", "connect the PTU to this port or fix the rig file's port");
  }
  identity_.model = "PTU";
  identity_.firmware = version;
  version_ = version;
  identity_.serial = "-";
  Query("I");  // immediate execution mode: position commands start at once
  for (PtuAxis& a : axes_) {
    ReadAxis(&a);
    ApplySpeed(&a);
    ReadAxis(&a);  // read back what the unit accepted
  }
  homed_ = false;
  moving_ = false;
  return identity_;
}

MotionState FlirPtu::State() {
  if (!homed_) return MotionState::kUnhomed;
  for (const PtuAxis& a : axes_) {
    if (a.has_target && std::llabs(Position(a) - a.target) > tolerance_) {
      return MotionState::kMoving;
    }
  }
  return MotionState::kIdle;
}

// Polls until every axis with a target stands at it (two equal polls). Throws on timeout.
void FlirPtu::WaitAt(milliseconds timeout, const std::string& what) {
  const auto deadline = Clock::now() + timeout;
  std::vector<long long> last(axes_.size(), LLONG_MIN);
  int still_polls = 0;  // consecutive polls with every axis standing still short of its target
  while (true) {
    bool done = true, still = true;
    for (std::size_t i = 0; i < axes_.size(); ++i) {
      const long long pos = Position(axes_[i]);
      if (axes_[i].has_target &&
          (std::llabs(pos - axes_[i].target) > tolerance_ || pos != last[i])) {
        done = false;
      }
      still = still && pos == last[i];
      was_away_ = was_away_ || pos != 0;
      last[i] = pos;
    }
    if (done) return;
    still_polls = still ? still_polls + 1 : 0;
    if (still_polls >= kStillPolls) StoppedShort(what, last);
    if (Clock::now() > deadline) {
      Stop();
      Fail("", what + " not done within " + std::to_string(timeout.count()) + " ms",
           "check for an obstruction, an overload or a stalled axis; then home");
    }
    std::this_thread::sleep_for(kPollPeriod);
  }
}

// Manual: R resets (calibrates) both axes; the '*' may come when the reset ends. The rig's speeds
// are set again, then the axes commanded to 0, where homing leaves them.
void FlirPtu::Home() {
  homed_ = false;
  if (restarted_) Reidentify();
  if (!Command("R", home_timeout_)) {
    LinkFail("no acknowledgement of the reset (R) within " +
                 std::to_string(home_timeout_.count()) + " ms",
             "check the unit's power and cable; then home again");
  }
  for (PtuAxis& a : axes_) {
    a.has_target = false;
    ApplySpeed(&a);  // a power cycle restored the unit's defaults
    ReadAxis(&a);
  }
  was_away_ = false;
  for (PtuAxis& a : axes_) MoveAxis(&a, 0);
  WaitAt(home_timeout_, "homing");
  homed_ = true;
  moving_ = false;
}

// One absolute position command. A lost '*' is followed by a check, never a blind resend: the
// axis moving or at the target means it was accepted; otherwise it is sent again.
void FlirPtu::MoveAxis(PtuAxis* a, long long position) {
  const std::string command = std::string(1, a->letter) + "P" + std::to_string(position);
  a->target = position;
  a->has_target = true;
  if (Command(command, timeout_)) return;
  const long long first = Position(*a);
  std::this_thread::sleep_for(kPollPeriod * 5);
  const long long second = Position(*a);
  if (first != second || std::llabs(second - position) <= tolerance_) return;
  if (!Command(command, timeout_)) {
    LinkFail("no acknowledgement of '" + command + "' (sent twice, the axis stood still)",
             "check the cable and the unit's power");
  }
}

void FlirPtu::StartMove(const StationPosition& target) {
  for (PtuAxis& a : axes_) {
    const double deg = AxisValue(target, a.axis);
    const long long position = std::llround(deg / a.deg_per_position);
    if (position < a.min_pos || position > a.max_pos) {
      Fail("", AxisText(a) + " target " + std::to_string(deg) + " deg is outside the unit's [" +
                   std::to_string(a.min_pos * a.deg_per_position) + ", " +
                   std::to_string(a.max_pos * a.deg_per_position) + "] deg",
           "narrow station.limits." + AxisText(a) + "_deg");
    }
  }
  if (!homed_) Fail("", "the unit is not homed", "home the station first");
  moving_ = true;
  was_away_ = false;
  for (const PtuAxis& a : axes_) was_away_ = was_away_ || (a.has_target && a.target != 0);
  for (PtuAxis& a : axes_) {
    const double deg = AxisValue(target, a.axis);
    MoveAxis(&a, std::llround(deg / a.deg_per_position));
  }
}

void FlirPtu::WaitSettled(milliseconds timeout) {
  WaitAt(timeout, "move");
  ConfirmStopped(timeout);
  moving_ = false;
}

void FlirPtu::ReadPosition(StationPosition* position) {
  for (const PtuAxis& a : axes_) {
    const double deg = static_cast<double>(StablePosition(a)) * a.deg_per_position;
    SetAxisValue(position, a.axis, deg);
  }
}

void FlirPtu::Stop() noexcept {
  try {
    Command("H", timeout_);  // manual: halt both axes
    moving_ = false;
  } catch (...) {
    // Best effort: the caller is already handling a failure.
  }
}

}  // namespace irdist::flir_ptu_internal

namespace irdist {
namespace {

using flir_ptu_internal::FlirPtu;
using flir_ptu_internal::kName;

[[noreturn]] void Invalid(const DeviceSpec& spec, const std::string& message) {
  InvalidEntry(spec, kName, message);
}

void Validate(const DeviceSpec& spec) {
  spec.CheckKnown({"speed_deg_s", "accel_deg_s2", "tolerance_positions", "retries",
                   "home_timeout_s", "reset_wait_s", "settle_ms"});
  if (spec.axes.empty()) Invalid(spec, "map pan and/or tilt in `axes:` ({pan: pan, tilt: tilt})");
  std::vector<std::string> used;
  for (const auto& [axis, address] : spec.axes) {
    if (axis == Axis::kSlide) Invalid(spec, "a pan-tilt unit cannot drive the slide");
    if (address != "pan" && address != "tilt") {
      Invalid(spec, "the PTU's axes are named pan and tilt, not '" + address + "'");
    }
    if (std::find(used.begin(), used.end(), address) != used.end()) {
      Invalid(spec, "the PTU axis '" + address + "' is mapped twice");
    }
    used.push_back(address);
  }
  for (const char* key : {"speed_deg_s", "accel_deg_s2"}) {
    if (spec.settings.count(key) && !(spec.Number(key, 0) > 0)) {
      Invalid(spec, key + std::string(" must be > 0"));
    }
  }
  for (const char* key : {"home_timeout_s", "reset_wait_s"}) {  // in ms later: 1e308 overflows
    if (spec.settings.count(key)) {
      const std::string refusal = bounds::kDurationS.Refusal(key, spec.Number(key, 0));
      if (!refusal.empty()) Invalid(spec, refusal);
    }
  }
  const std::string tolerance = bounds::kToleranceSteps.Refusal(  // cast to an integer later
      "tolerance_positions", spec.Number("tolerance_positions", 0));
  if (!tolerance.empty()) Invalid(spec, tolerance);
  const double retries = spec.Number("retries", 4);
  if (retries < 0 || retries > 10) Invalid(spec, "retries must be 0-10");
}

// Lines end with "\r" (manual: a command ends with a delimiter, [SPACE] or [ENTER]; a carriage
// return is [ENTER] and also ends the line for readers that execute whole lines only); 9600 baud,
// replies within 1000 ms.
DriverInfo MakePtuInfo() {
  DriverInfo info = SerialDriverInfo<FlirPtu>(kName, "\r", 9600, 1000, {"motion"}, Validate);
  info.cr_ends_reply = true;  // the manuals' replies end with CR alone; CR LF is read too
  return info;
}

}  // namespace

IRDIST_REGISTER_DRIVER(flir_ptu, MakePtuInfo());

}  // namespace irdist
