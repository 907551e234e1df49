// The emulator of a FLIR (formerly Directed Perception) PTU-E series pan-tilt unit speaking its
// ASCII command set (driver `flir_ptu`), written from the public PTU command reference:
// two-letter commands, a signed integer argument for the settable ones, the same letters alone
// as the query; every command answered by "*" (success, with the value for a query) or "!"
// (an error with its text), each reply ending CR LF, or CR alone (`reply_line_end: cr`, as the
// manuals' examples show). Positions are the unit's native positions; their size in arc seconds
// is what PR / TR report.
//
// A reset (R, and the reset at power-up) takes `reset_s` besides the axes' return to 0: the
// unit reads nothing meanwhile, so commands sent during it wait in the line and are answered,
// in order, once it ends (after a client gave up, its successor reads those stale replies).
// A power cycle (not the first power-up, which no client sees) prints the controller's banner
// (its version text) and "Initializing..." as it starts, as the PTU manuals' power-up shows;
// with echo on (`echo: true`, the power-up echo), each command sent during the power-up reset
// is echoed at once and answered when the reset ends.
// A limit hit (fault `limit_hit_axis`: the axis stalls halfway through its next move) is
// reported unsolicited as "!P" or "!T": the unit lost synchrony and needs a reset.
//
// Commands (case-insensitive; several may share a line, separated by spaces):
//   PP/TP [pos]   absolute position (query: the current, instantaneous position)
//   PO/TO [pos]   position offset from the current position (query: target - current)
//   PR/TR         resolution, arc seconds per position
//   PS/TS [pos/s] speed;  PA/TA [pos/s^2] acceleration
//   PN/PX/TN/TX   minimum / maximum position (query)
//   A             await: answers once both axes have stopped
//   R             reset: recalibrates both axes to 0 (answers when done)
//   H, HP, HT     halt both / pan / tilt
//   V             firmware version
//   FT / FV       terse / verbose feedback;  EE / ED echo on / off;  I immediate mode
//   PU/PL/PB [..] upper / lower / base speed (PS/TS outside [PL, PU] is refused);
//   PH/PM [R|L|O|H] power modes
//   LE / LD, CI / CV   limit enforcement, control mode (accepted)
// Terse replies give the bare value ("* 1000"), verbose ones a sentence.

#include <algorithm>
#include <cctype>
#include <cmath>
#include <sstream>

#include "sim/line_device.h"

namespace irdist::sim {
namespace {

struct PtuAxisConfig {
  double resolution_arcsec = 92.5714;
  long min_pos = -6000, max_pos = 6000;
  double speed_pos_s = 2000.0, accel_pos_s2 = 4000.0;
};

struct PtuConfig {
  PtuAxisConfig pan;
  PtuAxisConfig tilt{46.2857, -3600, 3600, 4000.0, 8000.0};
  double max_speed_pos_s = 12000.0;
  std::string version = "Pan-Tilt Controller v3.4.2 (emulated, irdist)";
  bool verbose = true;
  bool echo = false;
  bool reset_on_power_up = true;
  std::string line_end = "\r\n";  // `reply_line_end`: crlf | cr
  double reset_s = 0.0;            // a reset's own duration (simulated seconds)
  std::string limit_hit_axis;      // fault: "pan" | "tilt" stalls on its next move, "!P"/"!T"
};

struct PtuAxis {
  std::string name;                // "Pan" | "Tilt"
  std::vector<std::string> rig;    // rig axes this PTU axis drives
  PtuAxisConfig config;
  double position = 0.0;           // positions
  double speed_pos_s = 0.0, accel_pos_s2 = 0.0;
  TrapezoidMove move;
  bool moving = false, stuck = false, limit_hit = false;
  double limit_hit_s = 0.0;  // when the limit_hit fault stops this move (halfway)
  double speed_bounds[3] = {12000.0, 0.0, 0.0};  // PU, PL, PB
  char hold_power = 'R', move_power = 'R';
  double Degrees() const { return position * config.resolution_arcsec / 3600.0; }
};

bool ParseInteger(const std::string& text, long* value) {
  if (text.empty()) return false;
  std::size_t i = (text[0] == '-' || text[0] == '+') ? 1 : 0;
  if (i == text.size()) return false;
  for (std::size_t j = i; j < text.size(); ++j) {
    if (!std::isdigit(static_cast<unsigned char>(text[j]))) return false;
  }
  *value = std::stol(text);
  return true;
}

// "PP1000 TP -20 A" -> {"PP1000", "TP-20", "A"}: an argument separated from its command by a
// space joins it.
std::vector<std::string> SplitCommands(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> commands;
  std::string word;
  long ignored = 0;
  while (in >> word) {
    if (!commands.empty() && ParseInteger(word, &ignored) &&
        std::isalpha(static_cast<unsigned char>(commands.back().back()))) {
      commands.back() += word;
    } else {
      commands.push_back(word);
    }
  }
  return commands;
}

class PtuEmulator : public LineDevice {
 public:
  PtuEmulator(World& world, const EmulatorSpec& spec, const DeviceKeys& keys, PtuConfig config,
              PtuAxis pan, PtuAxis tilt)
      : LineDevice(world, spec.name, keys.faults, spec.seed), config_(std::move(config)) {
    axes_[0] = std::move(pan);
    axes_[1] = std::move(tilt);
    limit_hit_pending_ = !config_.limit_hit_axis.empty();
    SetReplyBitFlip(keys.flip);
    std::lock_guard<std::mutex> lock(state_mutex_);
    ResetToPowerOn();
  }

  // The serving thread calls this class's hooks: stop it before the members go.
  ~PtuEmulator() override { Stop(); }

 protected:
  std::string Terminators() const override { return "\r\n"; }
  std::string HandleMessage(const std::string& message) override;
  void Advance(double now_s) override;
  void ResetToPowerOn() override;

 private:
  std::string Execute(std::string command);
  std::string AxisCommand(PtuAxis& axis, char what, const std::string& argument);
  std::string Position(PtuAxis& axis, bool offset, const std::string& argument);
  std::string Rate(PtuAxis& axis, bool speed, const std::string& argument);
  std::string Limit(const PtuAxis& axis, bool maximum) const;
  std::string SpeedBound(PtuAxis& axis, char what, const std::string& argument);
  std::string PowerMode(PtuAxis& axis, char what, const std::string& argument);
  std::string Ok(const std::string& terse, const std::string& verbose) const;
  void MoveTo(PtuAxis& axis, double target);
  void Halt(PtuAxis& axis);
  std::string AwaitStop();
  std::string Reset();
  std::string Run(const std::string& message, bool echo);
  std::string Drain();
  std::string WithLineEnd(const std::string& replies) const;

  void HitLimit(PtuAxis& axis, double now_s);

  PtuConfig config_;
  PtuAxis axes_[2];
  bool verbose_ = true, echo_ = false;
  double busy_until_s_ = 0.0;       // a reset in progress: nothing is read until then
  bool limit_hit_pending_ = false;  // the limit_hit_axis fault has not struck yet
  bool powered_ = false;            // past the first power-up (a later one prints its banner)
  std::vector<std::string> deferred_;  // messages received during the power-up reset
  bool draining_ = false;              // running deferred_ (Advance re-enters through A, R)
};

void PtuEmulator::ResetToPowerOn() {
  verbose_ = config_.verbose;
  echo_ = config_.echo;
  for (PtuAxis& axis : axes_) {
    axis.speed_pos_s = axis.config.speed_pos_s;
    axis.accel_pos_s2 = axis.config.accel_pos_s2;
    axis.speed_bounds[0] = config_.max_speed_pos_s;
    axis.speed_bounds[1] = axis.speed_bounds[2] = 0.0;
    axis.hold_power = axis.move_power = 'R';
    Halt(axis);
    // The power-up reset calibration: the axis finds its index and returns to 0.
    if (config_.reset_on_power_up) MoveTo(axis, 0.0);
  }
  if (config_.reset_on_power_up) busy_until_s_ = Now() + config_.reset_s;
  deferred_.clear();  // what the unit had not run yet is lost with the power
  if (powered_ && config_.reset_on_power_up) {
    SendUnsolicited(WithLineEnd(config_.version + "\r\nInitializing...\r\n"));
  }
  powered_ = true;
  Advance(Now());
}

// The limit_hit_axis fault: the axis stops where it is and the unit reports it on its own.
void PtuEmulator::HitLimit(PtuAxis& axis, double now_s) {
  axis.position = axis.move.Position(now_s);
  Halt(axis);
  axis.limit_hit = false;
  limit_hit_pending_ = false;
  SendUnsolicited(std::string(axis.name == "Pan" ? "!P" : "!T") + config_.line_end);
}

void PtuEmulator::Advance(double now_s) {
  // The commands received during the power-up reset, once it ends (only on the serving thread:
  // A and R wait in simulated time).
  if (now_s >= busy_until_s_ && !deferred_.empty() && !draining_ && HasCurrentLock()) {
    SendUnsolicited(Drain());
  }
  std::map<std::string, double> rig;
  bool any_moving = false;
  for (PtuAxis& axis : axes_) {
    if (axis.moving && axis.limit_hit && now_s >= axis.limit_hit_s) HitLimit(axis, now_s);
    if (axis.moving) {
      if (!axis.stuck) axis.position = axis.move.Position(now_s);
      if (axis.move.Done(now_s)) axis.moving = false;
    }
    any_moving = any_moving || axis.moving;
    for (const std::string& name : axis.rig) rig[name] = axis.Degrees();
  }
  WriteWorldAxes(world(), this, rig, any_moving);
}

std::string PtuEmulator::HandleMessage(const std::string& message) {
  // The power-up reset: the message is echoed at once and run when the reset ends.
  if (Now() < busy_until_s_ && !draining_) {
    deferred_.push_back(message);
    return echo_ ? WithLineEnd(message + "\r\n") : "";
  }
  const std::string earlier = Drain();  // those received during a reset come first
  return earlier + WithLineEnd(Run(message, echo_));
}

// The replies to the messages received during the power-up reset, in order.
std::string PtuEmulator::Drain() {
  std::vector<std::string> messages;
  messages.swap(deferred_);
  draining_ = true;
  std::string replies;
  for (const std::string& message : messages) replies += WithLineEnd(Run(message, false));
  draining_ = false;
  return replies;
}

std::string PtuEmulator::Run(const std::string& message, bool echo) {
  std::string replies = echo ? message + "\r\n" : "";
  for (const std::string& command : SplitCommands(message)) replies += Execute(command);
  return replies;
}

// CR LF as written by the handlers, or CR alone (`reply_line_end: cr`).
std::string PtuEmulator::WithLineEnd(const std::string& replies) const {
  if (config_.line_end == "\r\n") return replies;
  std::string out;
  for (std::size_t i = 0; i < replies.size(); ++i) {
    if (replies.compare(i, 2, "\r\n") == 0) {
      out += config_.line_end;
      ++i;
    } else {
      out += replies[i];
    }
  }
  return out;
}

std::string PtuEmulator::Ok(const std::string& terse, const std::string& verbose) const {
  const std::string& text = verbose_ ? verbose : terse;
  return text.empty() ? "*\r\n" : "* " + text + "\r\n";
}

std::string PtuEmulator::Execute(std::string command) {
  for (char& c : command) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  if (command == "A") return AwaitStop();
  if (command == "R") return Reset();
  if (command == "V") return Ok(config_.version, config_.version);
  if (command == "H" || command == "HP" || command == "HT") {
    if (command != "HT") Halt(axes_[0]);
    if (command != "HP") Halt(axes_[1]);
    return Ok("", "");
  }
  if (command == "FT" || command == "FV") {
    verbose_ = command == "FV";
    return Ok("", "");
  }
  if (command == "EE" || command == "ED") {
    echo_ = command == "EE";
    return Ok("", "");
  }
  if (command == "I" || command == "LE" || command == "LD" || command == "CI" || command == "CV") {
    return Ok("", "");  // immediate mode, limit enforcement, control mode: no effect here
  }
  if (command.size() >= 2 && (command[0] == 'P' || command[0] == 'T')) {
    return AxisCommand(axes_[command[0] == 'P' ? 0 : 1], command[1], command.substr(2));
  }
  return "! Illegal command\r\n";
}

std::string PtuEmulator::AxisCommand(PtuAxis& axis, char what, const std::string& argument) {
  switch (what) {
    case 'P': return Position(axis, false, argument);
    case 'O': return Position(axis, true, argument);
    case 'S': return Rate(axis, true, argument);
    case 'A': return Rate(axis, false, argument);
    case 'U':
    case 'L':
    case 'B': return SpeedBound(axis, what, argument);
    case 'H':
    case 'M': return PowerMode(axis, what, argument);
    case 'N': return argument.empty() ? Limit(axis, false) : "! Illegal argument\r\n";
    case 'X': return argument.empty() ? Limit(axis, true) : "! Illegal argument\r\n";
    case 'R': {
      if (!argument.empty()) return "! Illegal argument\r\n";
      std::ostringstream value;
      value << axis.config.resolution_arcsec;
      return Ok(value.str(), value.str() + " seconds arc per " + axis.name + " position");
    }
    default: return "! Illegal command\r\n";
  }
}

std::string PtuEmulator::Position(PtuAxis& axis, bool offset, const std::string& argument) {
  const long current = std::lround(axis.position);
  if (argument.empty()) {
    const long value = offset ? std::lround(axis.moving ? axis.move.Target() - axis.position : 0.0)
                              : current;
    return Ok(std::to_string(value), std::string(offset ? "Target offset of " : "Current ") +
                                         axis.name + " position is " + std::to_string(value));
  }
  long value = 0;
  if (!ParseInteger(argument, &value)) return "! Illegal argument\r\n";
  const long target = offset ? current + value : value;
  if (target > axis.config.max_pos) {
    return "! Maximum allowable " + axis.name + " position exceeded\r\n";
  }
  if (target < axis.config.min_pos) {
    return "! Minimum allowable " + axis.name + " position exceeded\r\n";
  }
  MoveTo(axis, static_cast<double>(target));
  return Ok("", "");
}

std::string PtuEmulator::Rate(PtuAxis& axis, bool speed, const std::string& argument) {
  double& rate = speed ? axis.speed_pos_s : axis.accel_pos_s2;
  const std::string what = speed ? "speed" : "acceleration";
  if (argument.empty()) {
    const std::string value = std::to_string(std::lround(rate));
    return Ok(value, axis.name + " " + what + " is " + value + " positions/sec" +
                         (speed ? "" : "^2"));
  }
  long value = 0;
  if (!ParseInteger(argument, &value)) return "! Illegal argument\r\n";
  if (value <= 0) return "! Minimum allowable " + axis.name + " " + what + " exceeded\r\n";
  if (speed && (value > config_.max_speed_pos_s || value > axis.speed_bounds[0])) {
    return "! Maximum allowable " + axis.name + " speed exceeded\r\n";
  }
  if (speed && value < axis.speed_bounds[1]) {
    return "! Minimum allowable " + axis.name + " speed exceeded\r\n";
  }
  rate = static_cast<double>(value);
  return Ok("", "");
}

std::string PtuEmulator::Limit(const PtuAxis& axis, bool maximum) const {
  const std::string value = std::to_string(maximum ? axis.config.max_pos : axis.config.min_pos);
  return Ok(value, std::string(maximum ? "Maximum " : "Minimum ") + axis.name + " position is " +
                       value);
}

// PU / PL / PB (and T...): upper, lower and base speed, kept and reported; the profile uses PS.
std::string PtuEmulator::SpeedBound(PtuAxis& axis, char what, const std::string& argument) {
  double& value = axis.speed_bounds[what == 'U' ? 0 : what == 'L' ? 1 : 2];
  const std::string name = what == 'U' ? "upper speed limit" : what == 'L' ? "lower speed limit"
                                                                           : "base speed";
  if (argument.empty()) {
    const std::string text = std::to_string(std::lround(value));
    return Ok(text, axis.name + " " + name + " is " + text + " positions/sec");
  }
  long set = 0;
  if (!ParseInteger(argument, &set) || set < 0) return "! Illegal argument\r\n";
  if (set > config_.max_speed_pos_s) return "! Maximum allowable " + axis.name + " speed exceeded\r\n";
  value = static_cast<double>(set);
  return Ok("", "");
}

// PH / PM (and T...): hold and move power modes, R(egular), L(ow), O(ff), H(igh).
std::string PtuEmulator::PowerMode(PtuAxis& axis, char what, const std::string& argument) {
  char& mode = what == 'H' ? axis.hold_power : axis.move_power;
  if (argument.empty()) {
    const std::string text(1, mode);
    return Ok(text, axis.name + (what == 'H' ? " hold" : " move") + " power mode is " + text);
  }
  if (argument.size() != 1 || std::string("RLOH").find(argument[0]) == std::string::npos) {
    return "! Illegal argument\r\n";
  }
  mode = argument[0];
  return Ok("", "");
}

void PtuEmulator::MoveTo(PtuAxis& axis, double target) {
  axis.stuck = Faults().stuck_axis != "" &&
               std::find(axis.rig.begin(), axis.rig.end(), Faults().stuck_axis) != axis.rig.end();
  axis.move = TrapezoidMove(axis.position, target, Now(), axis.speed_pos_s, axis.accel_pos_s2);
  axis.moving = true;
  axis.limit_hit = limit_hit_pending_ && target != axis.position &&
                   config_.limit_hit_axis == (axis.name == "Pan" ? "pan" : "tilt");
  axis.limit_hit_s = Now() + 0.5 * axis.move.DurationS();
  NoteMoveStarted();
}

void PtuEmulator::Halt(PtuAxis& axis) {
  axis.move = TrapezoidMove();
  axis.moving = false;
}

std::string PtuEmulator::AwaitStop() {
  WaitInSimTime(CurrentLock(), [this] { return !axes_[0].moving && !axes_[1].moving; });
  return Ok("", "");
}

std::string PtuEmulator::Reset() {
  busy_until_s_ = Now() + config_.reset_s;
  for (PtuAxis& axis : axes_) {
    axis.limit_hit = false;
    MoveTo(axis, 0.0);
    axis.limit_hit = false;  // the reset re-synchronises; no fault strikes during it
  }
  WaitInSimTime(CurrentLock(), [this] { return Now() >= busy_until_s_; });
  return AwaitStop();
}

// ----------------------------------------------------------------------------------------------
// Construction from the rig file.

const std::vector<std::string> kPtuKeys = {
    "pan_resolution_arcsec", "tilt_resolution_arcsec", "pan_min_pos",     "pan_max_pos",
    "tilt_min_pos",          "tilt_max_pos",           "pan_speed_pos_s", "tilt_speed_pos_s",
    "pan_accel_pos_s2",      "tilt_accel_pos_s2",      "max_speed_pos_s", "version",
    "verbose",               "echo",                   "reset_on_power_up",
    "reply_line_end",        "reset_s",                "limit_hit_axis"};

PtuAxisConfig ReadAxisConfig(const DeviceKeys& keys, const std::string& prefix,
                             PtuAxisConfig c) {
  c.resolution_arcsec = keys.Number(prefix + "_resolution_arcsec", c.resolution_arcsec);
  c.min_pos = std::lround(keys.Number(prefix + "_min_pos", static_cast<double>(c.min_pos)));
  c.max_pos = std::lround(keys.Number(prefix + "_max_pos", static_cast<double>(c.max_pos)));
  c.speed_pos_s = keys.Number(prefix + "_speed_pos_s", c.speed_pos_s);
  c.accel_pos_s2 = keys.Number(prefix + "_accel_pos_s2", c.accel_pos_s2);
  if (!(c.resolution_arcsec > 0)) keys.Fail(prefix + "_resolution_arcsec", "must be > 0");
  if (!(c.min_pos < c.max_pos)) keys.Fail(prefix + "_max_pos", "must exceed the minimum");
  if (!(c.speed_pos_s > 0)) keys.Fail(prefix + "_speed_pos_s", "must be > 0");
  if (!(c.accel_pos_s2 > 0)) keys.Fail(prefix + "_accel_pos_s2", "must be > 0");
  return c;
}

std::unique_ptr<DeviceEmulator> CreatePtu(World& world, const EmulatorSpec& spec) {
  const DeviceKeys keys = ReadDeviceKeys(spec, kPtuKeys);
  PtuConfig c;
  c.pan = ReadAxisConfig(keys, "pan", c.pan);
  c.tilt = ReadAxisConfig(keys, "tilt", c.tilt);
  c.max_speed_pos_s = keys.Number("max_speed_pos_s", c.max_speed_pos_s);
  c.version = keys.Text("version", c.version);
  c.verbose = keys.Boolean("verbose", c.verbose);
  c.echo = keys.Boolean("echo", c.echo);
  c.reset_on_power_up = keys.Boolean("reset_on_power_up", c.reset_on_power_up);
  const std::string line_end = keys.Text("reply_line_end", "crlf");
  if (line_end != "crlf" && line_end != "cr") keys.Fail("reply_line_end", "must be crlf or cr");
  c.line_end = line_end == "cr" ? "\r" : "\r\n";
  c.reset_s = keys.Number("reset_s", c.reset_s);
  if (!(c.reset_s >= 0)) keys.Fail("reset_s", "must be >= 0");
  c.limit_hit_axis = keys.Text("limit_hit_axis", "");
  if (!c.limit_hit_axis.empty() && c.limit_hit_axis != "pan" && c.limit_hit_axis != "tilt") {
    keys.Fail("limit_hit_axis", "must be pan or tilt");
  }
  PtuAxis pan;
  pan.name = "Pan";
  pan.config = c.pan;
  PtuAxis tilt;
  tilt.name = "Tilt";
  tilt.config = c.tilt;
  for (const auto& [rig_axis, ptu_axis] : keys.axes) {
    if (!IsRigAxis(rig_axis)) keys.Fail("axes", "unknown rig axis '" + rig_axis + "'");
    if (ptu_axis != "pan" && ptu_axis != "tilt") {
      keys.Fail("axes", "station.devices." + spec.name + ".axes." + rig_axis +
                            " must be pan or tilt, not '" + ptu_axis + "'");
    }
    (ptu_axis == "pan" ? pan : tilt).rig.push_back(rig_axis);
  }
  return std::make_unique<PtuEmulator>(world, spec, keys, c, std::move(pan), std::move(tilt));
}

}  // namespace

IRDIST_REGISTER_EMULATOR(flir_ptu, (EmulatorInfo{"flir_ptu", &CreatePtu}));

}  // namespace irdist::sim
