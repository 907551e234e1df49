// The FLIR (formerly Directed Perception) PTU driver (docs/devices/flir_ptu.md): a PTU-E series
// pan-tilt unit as the motion role for pan and tilt. Written from the "Pan-Tilt Unit (E Series)
// Command Reference Manual" and the PTU-D46 user's manual's command reference: commands end with
// a delimiter (CR, [ENTER]), replies start with '*' (done) or '!' (error); positions are integers in
// the unit's native steps, whose size PR/TR report in seconds of arc.
//
// The protocol has no request ids: replies are matched by order, one per command. Echo is
// switched off (ED) and feedback set terse (FT) at connection; the parser still takes the text
// after the first '*' or '!' so an echoed command or verbose feedback parses the same.

#include <algorithm>
#include <cctype>
#include <climits>
#include <cmath>
#include <sstream>
#include <thread>

#include "base/bounds.h"
#include "station/axes_motion.h"
#include "station/driver.h"
#include "station/line_query.h"
#include "station/serial_driver.h"

namespace irdist {
namespace {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

constexpr char kName[] = "flir_ptu";
constexpr double kArcsecPerDeg = 3600.0;
constexpr milliseconds kPollPeriod{10};
constexpr int kStillPolls = 15;  // polls standing still, away from the target: stopped short
constexpr milliseconds kQuietAfterVersion{200};  // SyncOnVersion: the line is quiet after V

struct PtuAxis {
  Axis axis = Axis::kPan;
  char letter = 'P';            // command prefix: P (pan) or T (tilt)
  double deg_per_position = 0;  // PR/TR (arc seconds) / 3600
  long long min_pos = 0, max_pos = 0;
  AxisSpeed speed;
  long long target = 0;
  bool has_target = false;
  long long speed_pos_s = 0;  // PS/TS as read at Identify (a power cycle restores defaults)
  long long upper_pos_s = 0, lower_pos_s = 0;  // PU/PL (TU/TL) speed bounds; 0: not read
};

// The unit's own limit-hit report: "!P" or "!T" alone on a line (manual: the axis hit a limit
// and lost synchrony; a reset is needed).
bool IsLimitHit(const std::string& line) {
  const std::size_t mark = line.find('!');
  if (mark == std::string::npos) return false;
  std::string text = line.substr(mark + 1);
  text.erase(0, text.find_first_not_of(' '));
  text.erase(text.find_last_not_of(' ') + 1);
  return text == "P" || text == "T";
}

// Speed, acceleration and speed-bound commands (PS, TA, PU...): a refusal is about speed.
bool IsRateCommand(const std::string& command) {
  return command.size() >= 2 && (command[0] == 'P' || command[0] == 'T') &&
         std::string("SAULB").find(command[1]) != std::string::npos;
}

// The first number among the words of `text` ("* 22", "* Current Pan position is 22").
bool FirstNumber(const std::string& text, double* value) {
  std::istringstream in(text);
  for (std::string word; in >> word;) {
    while (!word.empty() && (word.back() == ',' || word.back() == '.')) word.pop_back();
    char* end = nullptr;
    const double v = std::strtod(word.c_str(), &end);
    if (!word.empty() && end == word.c_str() + word.size() && std::isfinite(v)) {
      *value = v;
      return true;
    }
  }
  return false;
}

class FlirPtu : public AxesMotionDriver<PtuAxis> {
 public:
  FlirPtu(const DeviceSpec& spec, std::unique_ptr<Transport> link)
      : spec_(spec), link_(std::move(link)), query_(link_.get(), QueryOptions(spec)) {
    identity_.kind = kName;
    identity_.port = spec.port;
    identity_.vendor = "FLIR";
    timeout_ = query_.options().reply_timeout;
    attempts_ = query_.options().attempts;
    tolerance_ = static_cast<long long>(spec.Number("tolerance_positions", 0));
    home_timeout_ = milliseconds(static_cast<long long>(spec.Number("home_timeout_s", 120) * 1000));
    reset_wait_ = milliseconds(static_cast<long long>(spec.Number("reset_wait_s", 60) * 1000));
    for (const auto& [axis, address] : spec.axes) {
      PtuAxis a;
      a.axis = axis;
      a.letter = address == "pan" ? 'P' : 'T';
      axes_.push_back(a);
    }
  }

  DeviceIdentity Identify() override;
  MotionState State() override;
  void Home() override;
  void StartMove(const StationPosition& target) override;
  void WaitSettled(milliseconds timeout) override;
  void ReadPosition(StationPosition* position) override;
  void Stop() noexcept override;
  void CheckAlive() override;

 private:
  LineQueryOptions QueryOptions(const DeviceSpec& spec);
  ReplyVerdict Judge(const std::string& command, const std::string& line, std::string* body) const;
  LineRequest Request(const std::string& command, std::string* body) const;
  std::string Query(const std::string& command);
  double QueryNumber(const std::string& command);
  bool Command(const std::string& command, milliseconds wait);
  long long Position(const PtuAxis& a) {
    return std::llround(QueryNumber(std::string(1, a.letter) + "P"));
  }
  long long StablePosition(const PtuAxis& a);
  void ReadAxis(PtuAxis* a);
  void ApplySpeed(PtuAxis* a);
  void MoveAxis(PtuAxis* a, long long position);
  void WaitAt(milliseconds timeout, const std::string& what);
  void TakePending(bool report_limit_hit);
  void SyncOnVersion();
  bool IsVersion(const std::string& line) const;
  [[noreturn]] void LimitHit(const std::string& line) const;
  void ReadSpeedBounds(PtuAxis* a);
  [[noreturn]] void StoppedShort(const std::string& what, const std::vector<long long>& positions);
  std::string AxisText(const PtuAxis& a) const { return AxisName(a.axis); }
  [[noreturn]] void Fail(const std::string& code, const std::string& message,
                         const std::string& fix) const {
    throw DeviceError(identity_, code, message, fix);
  }
  // A link failure naming the driver and the rig entry ("flir_ptu 'head': ...") and the port.
  [[noreturn]] void LinkFail(const std::string& message, const std::string& fix) const {
    throw LinkError(std::string(kName) + " '" + spec_.name + "': " + message, spec_.port, fix);
  }

  DeviceSpec spec_;
  std::unique_ptr<Transport> link_;
  LineQuery query_;  // after link_: it writes and reads through it
  DeviceIdentity identity_;
  milliseconds timeout_{1000};
  milliseconds home_timeout_{120000};
  milliseconds reset_wait_{60000};  // a unit silent this long after a lost reply is gone
  int attempts_ = 3;
  std::string version_;       // the unit's V answer: the resynchronisation marker
  bool out_of_step_ = false;  // a reply was lost: resynchronise before the next command
  long long tolerance_ = 0;
  bool homed_ = false;
  bool moving_ = false;
  bool was_away_ = false;  // an axis stood or was seen away from 0 since the move began
};

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
  };
  options.after_miss = [this] { out_of_step_ = true; };
  return options;
}

// A command's reply: the text after '*' (into *body). A line with neither '*' nor '!' (a banner,
// a bare echo, noise) is passed over. A '!' reply is a DeviceError carrying the unit's message.
ReplyVerdict FlirPtu::Judge(const std::string& command, const std::string& line,
                            std::string* body) const {
  const std::size_t mark = line.find_first_of("*!");
  if (mark == std::string::npos) return ReplyVerdict::kSkip;
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

// Manual: "!P" / "!T": the axis hit a limit and lost synchrony.
void FlirPtu::LimitHit(const std::string& line) const {
  const bool pan = line.find('P', line.find('!')) != std::string::npos;
  Fail(line, std::string(pan ? "pan" : "tilt") + " axis hit its limit (the unit's own report)",
       "the unit lost synchrony: check for an obstruction, then home (reset) it and resume");
}

// The lines that arrived unasked since the last reply (late replies, the unit's reports): a
// limit hit among them is reported (once homed), the rest dropped.
void FlirPtu::TakePending(bool report_limit_hit) {
  for (const std::string& line : link_->ReadPending()) {
    if (report_limit_hit && homed_ && IsLimitHit(line)) {
      homed_ = false;
      LimitHit(line);
    }
  }
}

bool FlirPtu::IsVersion(const std::string& line) const {
  const std::size_t mark = line.find('*');
  if (mark == std::string::npos) return false;
  if (!version_.empty()) return line.find(version_, mark) != std::string::npos;
  std::string upper = line.substr(mark);
  for (char& c : upper) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return upper.find("PAN-TILT") != std::string::npos || upper.find("PTU") != std::string::npos;
}

// Sends V and reads until its answer, then on until the line is quiet: every other line answers
// an earlier command (stale replies of a reset, of a previous session, whose own V may answer
// first). A resetting unit answers nothing, for up to reset_wait_s; a device that answers but
// never as a PTU is refused after `attempts` V's.
void FlirPtu::SyncOnVersion() {
  TakePending(true);
  const auto deadline = Clock::now() + reset_wait_;
  int answered = 0, unanswered = 0;
  std::string heard;
  link_->WriteLine("V");
  while (true) {
    if (Clock::now() >= deadline) {
      if (answered > 0) break;
      LinkFail("no answer to V within reset_wait_s (" + std::to_string(reset_wait_.count()) +
                   " ms)" + (heard.empty() ? "" : "; last heard '" + heard + "'"),
               "check the unit's power, cable and baud rate (PTU default 9600)");
    }
    std::string line;
    try {
      // Replies come in order: after a version only the answers to the other V's can follow,
      // back to back (a 50-character line takes 52 ms at 9600 baud).
      line = link_->ReadLine(answered > 0 ? std::min(timeout_, kQuietAfterVersion) : timeout_);
    } catch (const LinkError&) {
      if (answered > 0) break;  // quiet after the version: nothing stale is left
      if (!heard.empty() && ++unanswered >= attempts_) {
        Fail(heard, "the device on this port answers, but never with a pan-tilt unit's version",
             "connect the PTU to this port or fix the rig file's port");
      }
      link_->WriteLine("V");
      continue;
    }
    if (IsLimitHit(line) && homed_) {
      homed_ = false;
      LimitHit(line);
    }
    if (IsVersion(line)) {
      ++answered;
    } else if (answered == 0) {
      heard = line;
    }
  }
  out_of_step_ = false;
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
    const double deg_s = spec_.Number("speed_deg_s", 0);
    const long long s = std::llround(deg_s / a->deg_per_position);
    const bool above = a->upper_pos_s > 0 && s > a->upper_pos_s;
    if (above || s < a->lower_pos_s) {
      const long long bound = above ? a->upper_pos_s : a->lower_pos_s;
      Fail(p + (above ? "U " : "L ") + std::to_string(bound),
           "speed_deg_s " + std::to_string(deg_s) + " is " + (above ? "above" : "below") +
               " the " + AxisText(*a) + " axis's " + (above ? "upper" : "lower") +
               " speed bound " + p + (above ? "U " : "L ") + std::to_string(bound) +
               " positions/s (" + std::to_string(bound * a->deg_per_position) + " deg/s)",
           "set station.devices." + spec_.name + ".speed_deg_s within the unit's speed bounds");
    }
    if (!Command(p + "S" + std::to_string(s), timeout_)) {
      LinkFail("no reply to " + p + "S", "check the cable");
    }
  }
  if (spec_.settings.count("accel_deg_s2")) {
    const long long s = std::llround(spec_.Number("accel_deg_s2", 0) / a->deg_per_position);
    if (!Command(p + "A" + std::to_string(s), timeout_)) {
      LinkFail("no reply to " + p + "A", "check the cable");
    }
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
  std::string upper = version;
  for (char& c : upper) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  if (upper.find("PAN-TILT") == std::string::npos && upper.find("PTU") == std::string::npos) {
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

// Every axis stands still and one is away from its target. Back at 0/0 (where the power-up reset
// leaves the unit) after being elsewhere, or with the rig's speed gone back to the default: the
// unit restarted. An axis stuck at 0 since the move began is not told apart from it.
void FlirPtu::StoppedShort(const std::string& what, const std::vector<long long>& positions) {
  Stop();
  bool at_power_up_pose = was_away_, speed_reset = false;
  std::string short_axes;
  for (std::size_t i = 0; i < axes_.size(); ++i) {
    at_power_up_pose = at_power_up_pose && positions[i] == 0;
    if (std::llabs(positions[i] - axes_[i].target) > tolerance_) {
      short_axes += (short_axes.empty() ? "" : ", ") + AxisText(axes_[i]) + " at " +
                    std::to_string(positions[i]) + " (target " +
                    std::to_string(axes_[i].target) + ")";
    }
    if (spec_.settings.count("speed_deg_s")) {
      const std::string p(1, axes_[i].letter);
      speed_reset = speed_reset || std::llround(QueryNumber(p + "S")) != axes_[i].speed_pos_s;
    }
  }
  if (homed_ && (at_power_up_pose || speed_reset)) {
    homed_ = false;
    moving_ = false;
    throw DeviceRestarted(identity_.Brief() + ": " + what + " ended with " + short_axes +
                              (speed_reset ? ", speeds reset" : ", at the power-up pose 0/0") +
                              ": the unit was power-cycled or reset; home it and retake",
                          false);
  }
  Fail("", what + " stopped short: " + short_axes,
       "check for an obstruction, an overload or a stalled axis; then home");
}

// Manual: R resets (calibrates) both axes; the '*' may come when the reset ends. The rig's speeds
// are set again, then the axes commanded to 0, where homing leaves them.
void FlirPtu::Home() {
  homed_ = false;
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

// At rest, an axis away from its target or speeds back to their defaults: the unit restarted
// (its power-up reset moves the axes and resets the settings).
void FlirPtu::CheckAlive() {
  for (const PtuAxis& a : axes_) {
    const long long pos = (!homed_ || moving_ || !a.has_target) ? Position(a) : StablePosition(a);
    if (!homed_ || moving_ || !a.has_target) continue;
    const bool moved = std::llabs(pos - a.target) > tolerance_;
    const bool reset = spec_.settings.count("speed_deg_s") &&
                       std::llround(QueryNumber(std::string(1, a.letter) + "S")) != a.speed_pos_s;
    if (moved || reset) {
      homed_ = false;
      throw DeviceRestarted(identity_.Brief() + ": " + AxisText(a) + " at " +
                                std::to_string(pos) + " instead of " + std::to_string(a.target) +
                                (reset ? " and its speed reset" : "") +
                                ": the unit was power-cycled or reset; home it and retake",
                            false);
    }
  }
}

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
