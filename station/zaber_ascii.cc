// The Zaber ASCII protocol driver (docs/devices/zaber_ascii.md): linear and rotary Zaber stages
// (firmware 6 and 7) as the motion role. Written from Zaber's ASCII Protocol Manual: command and
// reply structure ("/device axis id command:CC" -> "@device axis id flag status warning data:CC"),
// message ids, the LRC checksum, reply flags (OK/RJ) and rejection reasons, warning flags, and the
// physical units of `pos`, `maxspeed` and `accel`.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <set>
#include <sstream>
#include <thread>

#include "base/bounds.h"
#include "station/axes_motion.h"
#include "station/driver.h"
#include "station/line_query.h"
#include "station/serial_driver.h"
#include "station/zaber_ascii_text.h"

namespace irdist {
namespace {

using namespace zaber_ascii_text;  // NOLINT: the protocol's own vocabulary

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

constexpr char kName[] = "zaber_ascii";
// Manual, settings `maxspeed` and `accel` (same units as the A-Series Set Target Speed / Set
// Acceleration): microsteps/s = maxspeed / 1.6384; microsteps/s^2 = accel x 10000 / 1.6384.
constexpr double kSpeedDataPerMicrostepS = 1.6384;
constexpr double kAccelDataPerMicrostepS2 = 1.6384 / 10000.0;
constexpr milliseconds kPollPeriod{10};
constexpr char kNoReplyFix[] =
    "check the cable, the baud rate (Zaber ASCII default 115200) and the device address in the "
    "rig file";

struct AxisState {
  Axis axis = Axis::kSlide;
  Address address;
  double unit_per_microstep = 0.0;  // mm (slide) or deg (pan/tilt) per microstep
  double origin = 0.0;              // mm or deg at microstep 0
  long long limit_min = 0, limit_max = 0;
  AxisSpeed speed;
  long long target = 0;
  bool has_target = false;
};

class ZaberAscii : public AxesMotionDriver<AxisState> {
 public:
  ZaberAscii(const DeviceSpec& spec, std::unique_ptr<Transport> link)
      : spec_(spec),
        link_(std::move(link)),
        query_(link_.get(), QueryOptionsOf(spec, 4, 500, "the Zaber device", kNoReplyFix)) {
    identity_.kind = kName;
    identity_.port = spec.port;
    identity_.vendor = "Zaber";
    timeout_ = query_.options().reply_timeout;
    checksum_ = spec.Text("checksum", "true") == "true";
    direction_ = spec.Number("direction", 1.0);
    tolerance_ = static_cast<long long>(spec.Number("tolerance_microsteps", 2));
    home_timeout_ = milliseconds(static_cast<long long>(spec.Number("home_timeout_s", 120) * 1000));
    reset_wait_ = milliseconds(static_cast<long long>(spec.Number("reset_wait_s", 60) * 1000));
    for (const auto& [axis, text] : spec.axes) {
      AxisState s;
      s.axis = axis;
      ParseAddress(text, &s.address);
      s.origin = spec.Number(axis == Axis::kSlide ? "origin_mm" : "origin_deg", 0.0);
      axes_.push_back(s);
    }
  }
  ~ZaberAscii() override = default;

  DeviceIdentity Identify() override;
  MotionState State() override;
  void Home() override;
  void StartMove(const StationPosition& target) override;
  void WaitSettled(milliseconds timeout) override;
  void ReadPosition(StationPosition* position) override;
  void Stop() noexcept override;
  void SetSpeed(Axis axis, double unit_per_s) override;
  void CheckAlive() override;

 private:
  std::string Compose(const Address& a, int axis, const std::string& command, int* id);
  ReplyVerdict Judge(const Address& a, int axis, int id, const std::string& line, Reply* reply);
  LineRequest Request(const Address& a, int axis, const std::string& command, Reply* reply,
                      bool numeric = false);
  Reply Query(const Address& a, int axis, const std::string& command, bool numeric = false);
  void AskThroughReset(const LineRequest& request, const NoReplyError& silent);
  long long QueryNumber(const Address& a, int axis, const std::string& command) {
    return Number(Query(a, axis, command, true), command);
  }
  void EnableReplyChecksums(const Address& a);
  bool Command(const Address& a, const std::string& command, Reply* reply);
  void ThrowIfRejected(const Reply& r, const std::string& command) const;
  long long Number(const Reply& r, const std::string& command) const;
  void IdentifyDevice(const Address& a);
  void ReadAxis(AxisState* s);
  void CheckFlag(const AxisState& s, const Reply& r) const;
  void IssueMove(AxisState* s, long long microsteps);
  bool Settled(AxisState* s);
  void WaitIdle(AxisState* s, milliseconds timeout, const std::string& what);
  double ToUnits(const AxisState& s, long long microsteps) const {
    return s.origin + direction_ * static_cast<double>(microsteps) * s.unit_per_microstep;
  }
  long long ToMicrosteps(const AxisState& s, double value) const {
    return std::llround((value - s.origin) / (direction_ * s.unit_per_microstep));
  }
  [[noreturn]] void Fail(const std::string& code, const std::string& message,
                         const std::string& fix) const {
    throw DeviceError(identity_, code, message, fix);
  }

  DeviceSpec spec_;
  std::unique_ptr<Transport> link_;
  LineQuery query_;  // after link_: it writes and reads through it
  DeviceIdentity identity_;
  milliseconds timeout_{500};
  milliseconds home_timeout_{120000};
  milliseconds reset_wait_{60000};  // an identified device silent this long after a miss is gone
  bool checksum_ = true;
  bool reply_checksums_ = false;  // comm.checksum is on: a reply without a checksum is damaged
  int unchecked_replies_ = 0;     // replies of the query in flight that came without checksum
  double direction_ = 1.0;
  long long tolerance_ = 2;
  int next_id_ = 0;
  bool identified_ = false;       // Identify() completed: a silence may be a reset, waited out
  bool homed_ = false;
  mutable bool restarted_ = false;  // a lost reference was reported: the next Home identifies
};

// "/device axis id command[:CC]" with the next message id (manual: ids 0-99), kept in *id.
std::string ZaberAscii::Compose(const Address& a, int axis, const std::string& command, int* id) {
  next_id_ = next_id_ % 99 + 1;
  *id = next_id_;
  const std::string body = std::to_string(a.device) + " " + std::to_string(axis) + " " +
                           std::to_string(next_id_) + " " + command;
  return "/" + body + (checksum_ ? ":" + Lrc(body) : "");
}

// The reply of (device, axis, id); other messages (alerts, info, stale replies to timed-out
// requests, garbled lines) are passed over.
ReplyVerdict ZaberAscii::Judge(const Address& a, int axis, int id, const std::string& line,
                               Reply* reply) {
  Reply r;
  bool checked = false;
  if (!ParseReply(line, false, &r, &checked)) return ReplyVerdict::kSkip;
  if (r.type != '@' || r.device != a.device || r.axis != axis || r.id != id) {
    return ReplyVerdict::kSkip;
  }
  if (reply_checksums_ && !checked) {  // comm.checksum is on: its checksum was damaged away
    ++unchecked_replies_;
    return ReplyVerdict::kRetry;
  }
  *reply = r;
  return ReplyVerdict::kMatch;
}

// One request to (device, axis): a fresh message id on every attempt, matched by the judge.
LineRequest ZaberAscii::Request(const Address& a, int axis, const std::string& command,
                                Reply* reply, bool numeric) {
  auto id = std::make_shared<int>(0);
  LineRequest request;
  request.query = command;
  request.device = "Zaber device " + std::to_string(a.device) + " (zaber_ascii)";
  request.compose = [this, a, axis, command, id] { return Compose(a, axis, command, id.get()); };
  request.judge = [this, a, axis, id, reply, numeric](const std::string& line) {
    const ReplyVerdict verdict = Judge(a, axis, *id, line, reply);
    // A numeric answer that is not numbers was damaged on the wire (no reply checksum caught
    // it): asked again. A rejection carries a reason, not a number.
    if (verdict == ReplyVerdict::kMatch && numeric && reply->flag == "OK" &&
        !IsIntegers(reply->data)) {
      return ReplyVerdict::kRetry;
    }
    return verdict;
  };
  return request;
}

// A query: safe to repeat, so a lost or damaged reply is retried with a new message id. When
// every reply came without its checksum, the device forgot comm.checksum (a factory reset):
// it is enabled again and the query asked once more.
Reply ZaberAscii::Query(const Address& a, int axis, const std::string& command, bool numeric) {
  Reply r;
  unchecked_replies_ = 0;
  try {
    query_.Ask(Request(a, axis, command, &r, numeric));
  } catch (const NoReplyError& silent) {
    if (unchecked_replies_ < query_.options().attempts) {
      AskThroughReset(Request(a, axis, command, &r, numeric), silent);
    } else {
      reply_checksums_ = false;
      EnableReplyChecksums(a);
      query_.Ask(Request(a, axis, command, &r, numeric));
    }
  }
  ThrowIfRejected(r, command);
  return r;
}

// An identified device silent through every attempt may be booting after a power cut (deaf and
// mute meanwhile, perhaps an alert when it is up): the query is asked again, each time with a new
// message id, until it answers or reset_wait_s ran out. Its reply then says whether the
// reference was lost (WR: a restart, CheckFlag). Before Identify a silent port is no device.
void ZaberAscii::AskThroughReset(const LineRequest& request, const NoReplyError& silent) {
  if (!identified_) throw silent;
  const auto deadline = Clock::now() + reset_wait_;
  while (Clock::now() < deadline) {
    if (query_.AskOnce(request, timeout_)) return;
  }
  throw LinkError(silent.device() + " silent for reset_wait_s (" +
                      std::to_string(reset_wait_.count()) + " ms) after '" + silent.query() + "'",
                  spec_.port,
                  "check the device's power and cable; a controller that takes longer to start "
                  "needs a larger reset_wait_s");
}

// Manual, setting comm.checksum (device scope): 1 makes the device checksum its replies (it
// verifies a command's checksum either way). From its acknowledgement on, a reply without a
// checksum is taken as damaged. A firmware without the setting (RJ) keeps unchecked replies.
void ZaberAscii::EnableReplyChecksums(const Address& a) {
  if (!checksum_) return;
  Reply r;
  query_.Ask(Request(a, 0, "set comm.checksum 1", &r));
  reply_checksums_ = r.flag == "OK";
}

// A motion command: sent once. False when its reply was lost (the caller checks the device's
// state before deciding anything).
bool ZaberAscii::Command(const Address& a, const std::string& command, Reply* reply) {
  if (!query_.AskOnce(Request(a, a.axis, command, reply), timeout_)) return false;
  ThrowIfRejected(*reply, command);
  return true;
}

void ZaberAscii::ThrowIfRejected(const Reply& r, const std::string& command) const {
  if (r.flag != "RJ") return;
  Fail("RJ " + r.data, "device " + std::to_string(r.device) + " axis " + std::to_string(r.axis) +
                           " rejected '" + command + "'",
       RejectionFix(r.data));
}

long long ZaberAscii::Number(const Reply& r, const std::string& command) const {
  std::size_t used = 0;
  long long value = 0;
  try {
    value = std::stoll(r.data, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != r.data.size()) {
    if (IsIntegers(r.data)) {  // one number per axis: a device-scope address
      Fail(r.data, "'" + command + "' answered '" + r.data + "', one value per axis",
           "map one axis per address in `axes:` (\"device axis\")");
    }
    Fail(r.data, "'" + command + "' answered '" + r.data + "', not a number (a damaged reply)",
         "check the cable and its shielding, the baud rate, and keep `checksum: true`");
  }
  return value;
}

void ZaberAscii::IdentifyDevice(const Address& a) {
  Reply id_reply;
  try {
    EnableReplyChecksums(a);
    id_reply = Query(a, 0, "get deviceid", true);
  } catch (const LinkError& e) {
    const auto* no_reply = dynamic_cast<const NoReplyError*>(&e);
    const std::string heard = no_reply != nullptr ? no_reply->last_heard() : "";
    Fail("", "no Zaber ASCII device answers at address " + std::to_string(a.device) +
                 (heard.empty() ? "" : " (heard '" + heard + "')"),
         "check that the port is the Zaber's (ls -l /dev/serial/by-id), its baud rate and that "
         "the device speaks the ASCII protocol");
  }
  identity_.model = "deviceid " + id_reply.data;
  identity_.serial = Query(a, 0, "get system.serial", true).data;
  identity_.firmware = Query(a, 0, "get version").data;
  const std::string want_id = spec_.Text("deviceid", "");
  if (!want_id.empty() && want_id != id_reply.data) {
    Fail(id_reply.data, "device " + std::to_string(a.device) + " is deviceid " + id_reply.data +
                            ", the rig file expects " + want_id,
         "connect the right stage or correct station.devices." + spec_.name + ".deviceid");
  }
  const std::string want_serial = spec_.Text("serial", "");
  if (!want_serial.empty() && want_serial != identity_.serial) {
    Fail(identity_.serial, "device " + std::to_string(a.device) + " has serial " +
                               identity_.serial + ", the rig file expects " + want_serial,
         "two stages may be swapped: check /dev/serial/by-id and the rig file");
  }
}

// Step size (rig file, or full step / the device's resolution), limits and speed of one axis.
void ZaberAscii::ReadAxis(AxisState* s) {
  const bool linear = s->axis == Axis::kSlide;
  const std::string unit = linear ? "um" : "deg";
  const double scale = linear ? 1e-3 : 1.0;  // um -> mm
  if (spec_.settings.count("microstep_" + unit)) {
    s->unit_per_microstep = spec_.Number("microstep_" + unit, 0.0) * scale;
  } else {
    const long long resolution = QueryNumber(s->address, s->address.axis, "get resolution");
    if (resolution <= 0) Fail(std::to_string(resolution), "resolution must be > 0", "set it");
    s->unit_per_microstep = spec_.Number("fullstep_" + unit, 0.0) * scale / resolution;
  }
  const Address& a = s->address;
  s->limit_min = QueryNumber(a, a.axis, "get limit.min");
  s->limit_max = QueryNumber(a, a.axis, "get limit.max");
  const double step = s->unit_per_microstep;
  s->speed.speed = QueryNumber(a, a.axis, "get maxspeed") / kSpeedDataPerMicrostepS * step;
  s->speed.acceleration =
      QueryNumber(a, a.axis, "get accel") / kAccelDataPerMicrostepS2 * step;
  s->speed.settle_ms = spec_.Number("settle_ms", 0.0);
  s->speed.home = ToUnits(*s, 0);
}

// Manual, setting `maxspeed`: the axis's speed limit for moves, in data units (microsteps/s x
// 1.6384); writable, taking effect for the moves that follow (a value out of its range: RJ
// BADDATA). A power cycle restores the stored value.
void ZaberAscii::SetSpeed(Axis axis, double unit_per_s) {
  for (AxisState& s : axes_) {
    if (s.axis != axis) continue;
    const long long data =
        std::llround(unit_per_s / s.unit_per_microstep * kSpeedDataPerMicrostepS);
    if (data < 1) {
      Fail(std::to_string(data), std::string(AxisName(axis)) + " speed " +
                                     std::to_string(unit_per_s) + " is below one data unit",
           "ask for a faster speed");
    }
    const std::string command = "set maxspeed " + std::to_string(data);
    Reply r;
    if (!Command(s.address, command, &r)) {
      throw LinkError(std::string(kName) + " '" + spec_.name + "': no reply to '" + command + "'",
                      spec_.port, kNoReplyFix);
    }
    s.speed.speed = static_cast<double>(data) / kSpeedDataPerMicrostepS * s.unit_per_microstep;
  }
}

DeviceIdentity ZaberAscii::Identify() {
  link_->Flush();
  identified_ = false;
  const std::string serial_before = identity_.serial;
  std::set<int> seen;
  for (AxisState& s : axes_) {
    if (seen.insert(s.address.device).second) IdentifyDevice(s.address);
    ReadAxis(&s);
  }
  if (!serial_before.empty() && identity_.serial != serial_before) {
    Fail(identity_.serial, "serial " + identity_.serial + " answers where " + serial_before +
                               " did before the restart",
         "another stage is on this port: check /dev/serial/by-id and the cabling");
  }
  homed_ = false;
  identified_ = true;
  return identity_;
}

// Faults and lost references, as typed errors. WR/WH after our own homing: a power cycle.
void ZaberAscii::CheckFlag(const AxisState& s, const Reply& r) const {
  const std::string where = std::string(AxisName(s.axis)) + " (device " +
                            std::to_string(s.address.device) + " axis " +
                            std::to_string(s.address.axis) + ")";
  if (Fault(r.warning)) {
    Fail(r.warning, where + " reports fault: " + FlagMeaning(r.warning),
         "clear the cause, then `warnings clear` and home again");
  }
  if (homed_ && Unreferenced(r.warning)) {
    restarted_ = true;
    throw DeviceRestarted(identity_.Brief() + ": " + where + " lost its home reference (" +
                              r.warning + ": " + FlagMeaning(r.warning) +
                              "): the device was power-cycled or reset; home it and retake",
                          false);
  }
}

MotionState ZaberAscii::State() {
  MotionState state = MotionState::kIdle;
  for (const AxisState& s : axes_) {
    const Reply r = Query(s.address, s.address.axis, "get pos", true);
    if (Fault(r.warning)) return MotionState::kFault;
    if (Unreferenced(r.warning)) state = MotionState::kUnhomed;
    if (r.status == "BUSY" && state == MotionState::kIdle) state = MotionState::kMoving;
  }
  return state;
}

void ZaberAscii::WaitIdle(AxisState* s, milliseconds timeout, const std::string& what) {
  const auto deadline = Clock::now() + timeout;
  while (true) {
    const Reply r = Query(s->address, s->address.axis, "get pos", true);
    CheckFlag(*s, r);
    if (r.status == "IDLE") return;
    if (Clock::now() > deadline) {
      Stop();
      Fail("", std::string(AxisName(s->axis)) + " still busy " + what + " after " +
                   std::to_string(timeout.count()) + " ms",
           "check for an obstruction or a stalled axis");
    }
    std::this_thread::sleep_for(kPollPeriod);
  }
}

void ZaberAscii::Home() {
  if (restarted_) {  // after a power cut: the same device, its settings and travel read again
    Identify();
    restarted_ = false;
  }
  homed_ = false;
  for (AxisState& s : axes_) {
    Query(s.address, s.address.axis, "warnings clear");
    Reply r;
    if (!Command(s.address, "home", &r)) {
      // Reply lost: homing is safe to repeat (manual), but only once we know it did not start.
      const Reply state = Query(s.address, s.address.axis, "get pos", true);
      if (state.status == "IDLE") Command(s.address, "home", &r);
    }
  }
  for (AxisState& s : axes_) {
    WaitIdle(&s, home_timeout_, "homing");
    const Reply r = Query(s.address, s.address.axis, "get pos", true);
    if (Unreferenced(r.warning) || Fault(r.warning)) {
      Fail(r.warning, std::string(AxisName(s.axis)) + " did not home: " + FlagMeaning(r.warning),
           "check the home sensor and that nothing blocks the travel");
    }
    s.target = Number(r, "get pos");
    s.has_target = true;
  }
  homed_ = true;
}

// Sends one absolute move. A lost reply is never answered by a blind resend: the device's
// state says whether the move started (BUSY), is done (at target) or never arrived (resend).
void ZaberAscii::IssueMove(AxisState* s, long long microsteps) {
  const std::string command = "move abs " + std::to_string(microsteps);
  Reply r;
  if (Command(s->address, command, &r)) return;
  const Reply state = Query(s->address, s->address.axis, "get pos", true);
  CheckFlag(*s, state);
  if (state.status == "BUSY" || std::llabs(Number(state, "get pos") - microsteps) <= tolerance_)
    return;
  if (!Command(s->address, command, &r)) {
    throw LinkError("no reply to '" + command + "' (sent twice, the device stayed idle)",
                    spec_.port, "check the cable and the device's power");
  }
}

void ZaberAscii::StartMove(const StationPosition& target) {
  for (AxisState& s : axes_) {
    const double value = AxisValue(target, s.axis);
    const long long microsteps = ToMicrosteps(s, value);
    if (microsteps < s.limit_min || microsteps > s.limit_max) {
      const double a = ToUnits(s, s.limit_min), b = ToUnits(s, s.limit_max);
      Fail("", std::string(AxisName(s.axis)) + " target " + std::to_string(value) +
                   " is outside the stage's travel [" + std::to_string(std::min(a, b)) + ", " +
                   std::to_string(std::max(a, b)) + "]",
           "narrow station.limits or correct origin_" +
               std::string(s.axis == Axis::kSlide ? "mm" : "deg") + "/direction");
    }
    IssueMove(&s, microsteps);
    s.target = microsteps;
    s.has_target = true;
  }
}

// One poll of one axis: true when it is idle within tolerance of its target.
bool ZaberAscii::Settled(AxisState* s) {
  const Reply r = Query(s->address, s->address.axis, "get pos", true);
  CheckFlag(*s, r);
  if (Unreferenced(r.warning)) {
    Fail(r.warning, std::string(AxisName(s->axis)) + " is not homed", "home the station first");
  }
  if (r.status == "BUSY") return false;
  const long long pos = Number(r, "get pos");
  if (std::llabs(pos - s->target) <= tolerance_) return true;
  Fail(r.warning, std::string(AxisName(s->axis)) + " stopped at " +
                      std::to_string(ToUnits(*s, pos)) + " short of " +
                      std::to_string(ToUnits(*s, s->target)) +
                      (r.warning == "--" ? "" : " (" + FlagMeaning(r.warning) + ")"),
       "check for an obstruction, the manual knob, or a stop from elsewhere; then home");
}

void ZaberAscii::WaitSettled(milliseconds timeout) {
  const auto deadline = Clock::now() + timeout;
  for (AxisState& s : axes_) {
    if (!s.has_target) continue;
    while (!Settled(&s)) {
      if (Clock::now() > deadline) {
        Stop();
        Fail("", std::string(AxisName(s.axis)) + " did not arrive within " +
                     std::to_string(timeout.count()) + " ms",
             "check for a stalled or blocked axis");
      }
      std::this_thread::sleep_for(kPollPeriod);
    }
  }
}

void ZaberAscii::ReadPosition(StationPosition* position) {
  for (const AxisState& s : axes_) {
    const Reply r = Query(s.address, s.address.axis, "get pos", true);
    CheckFlag(s, r);
    SetAxisValue(position, s.axis, ToUnits(s, Number(r, "get pos")));
  }
}

void ZaberAscii::Stop() noexcept {
  const bool identified = identified_;
  identified_ = false;  // an exit path never waits out a silent device
  for (AxisState& s : axes_) {
    try {
      Reply r;
      Command(s.address, "stop", &r);
      const auto deadline = Clock::now() + std::chrono::seconds(5);
      while (Query(s.address, s.address.axis, "get pos", true).status == "BUSY" &&
             Clock::now() < deadline) {
        std::this_thread::sleep_for(kPollPeriod);
      }
    } catch (...) {
      // Best effort: the caller is already handling a failure.
    }
  }
  identified_ = identified;
}

void ZaberAscii::CheckAlive() {
  for (const AxisState& s : axes_) CheckFlag(s, Query(s.address, s.address.axis, "get pos", true));
}

[[noreturn]] void Invalid(const DeviceSpec& spec, const std::string& message) {
  InvalidEntry(spec, kName, message);
}

void CheckStepKeys(const DeviceSpec& spec, const std::string& unit) {
  const bool micro = spec.settings.count("microstep_" + unit) > 0;
  const bool full = spec.settings.count("fullstep_" + unit) > 0;
  if (micro == full) {
    Invalid(spec, "give exactly one of microstep_" + unit + " and fullstep_" + unit +
                      " (the stage's datasheet step size)");
  }
  const std::string key = (micro ? "microstep_" : "fullstep_") + unit;
  if (spec.Number(key, 0.0) <= 0.0) Invalid(spec, key + " must be > 0");
}

void Validate(const DeviceSpec& spec) {
  spec.CheckKnown({"microstep_um", "fullstep_um", "microstep_deg", "fullstep_deg", "origin_mm",
                   "origin_deg", "direction", "deviceid", "serial", "tolerance_microsteps",
                   "retries", "home_timeout_s", "reset_wait_s", "settle_ms", "checksum"});
  if (spec.axes.empty()) Invalid(spec, "map at least one axis in `axes:` (e.g. {slide: \"1\"})");
  bool linear = false, angular = false;
  std::set<std::pair<int, int>> used;
  for (const auto& [axis, text] : spec.axes) {
    Address a;
    if (!ParseAddress(text, &a)) {
      Invalid(spec, "axis address '" + text + "' of " + AxisName(axis) +
                        " must be \"device\" or \"device axis\" (device 1-99, axis 1-9)");
    }
    if (!used.insert({a.device, a.axis}).second) Invalid(spec, "address '" + text + "' used twice");
    (axis == Axis::kSlide ? linear : angular) = true;
  }
  if (linear) CheckStepKeys(spec, "um");
  if (angular) CheckStepKeys(spec, "deg");
  const double direction = spec.Number("direction", 1.0);
  if (direction != 1.0 && direction != -1.0) Invalid(spec, "direction must be 1 or -1");
  const std::string tolerance = bounds::kToleranceSteps.Refusal(  // cast to an integer later
      "tolerance_microsteps", spec.Number("tolerance_microsteps", 2));
  if (!tolerance.empty()) Invalid(spec, tolerance);
  if (spec.Number("retries", 4) < 0 || spec.Number("retries", 4) > 20) Invalid(spec, "retries 0-20");
  const std::string home_wait = bounds::kDurationS.Refusal("home_timeout_s",
                                                           spec.Number("home_timeout_s", 120));
  if (!home_wait.empty()) Invalid(spec, home_wait);  // in ms later: 1e308 would overflow
  const std::string reset_wait = bounds::kDurationS.Refusal("reset_wait_s",
                                                            spec.Number("reset_wait_s", 60));
  if (!reset_wait.empty()) Invalid(spec, reset_wait);
  const std::string checksum = spec.Text("checksum", "true");
  if (checksum != "true" && checksum != "false") Invalid(spec, "checksum must be true or false");
}

// Lines end with "\n" (manual: CR, LF or both end a command; replies end with CR LF); 115200
// baud, replies within 500 ms.
DriverInfo MakeZaberInfo() {
  return SerialDriverInfo<ZaberAscii>(kName, "\n", 115200, 500, {"motion"}, Validate);
}

}  // namespace

IRDIST_REGISTER_DRIVER(zaber_ascii, MakeZaberInfo());

}  // namespace irdist
