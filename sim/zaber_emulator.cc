// The emulator of a Zaber motion controller speaking the Zaber ASCII protocol (driver
// `zaber_ascii`), written from Zaber's public "ASCII Protocol Manual" (message format, replies,
// warning flags, commands and settings). One emulator serves one serial port: every
// (device address, axis number) that `station.devices.<name>.axes` maps to a rig axis is one
// stage on the daisy chain. Positions are microsteps; motion is trapezoidal in simulated time.
//
// Protocol summary (as implemented):
//   command  /[device] [axis] [message id] command words [data][:CC]\n   (CR LF accepted)
//   reply    @dd a [id] OK|RJ IDLE|BUSY flag data[:CC]\r\n
// The checksum CC (two hex digits) is the two's complement of the 8-bit sum of the bytes between
// the leading '/' or '@' and the ':'; a command carrying one is verified (a mismatch is rejected
// with BADDATA). Replies carry one only while the device setting comm.checksum is 1 (default 0;
// kept across a power cycle, as the manual's non-volatile settings). Alerts are not emitted
// (`set comm.alert 0` only). Warning flags: FS (stalled: a move ended away from its target), WR
// (no reference position: after power-up until homed), "--" none.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <sstream>

#include "sim/line_device.h"

namespace irdist::sim {
namespace {

// Zaber's data units: speed data = microsteps/s x 1.6384, acceleration data = microsteps/s^2 x
// 1.6384 / 10000 (the manual's unit conversion table).
constexpr double kSpeedDataPerUstepS = 1.6384;
constexpr double kAccelDataPerUstepS2 = 1.6384 / 10000.0;

struct ZaberConfig {
  int device_id = 50081;             // `get deviceid`
  long serial = 1234567;             // `get system.serial`
  std::string version = "7.38";      // `get version`
  int resolution = 64;               // microsteps per full step
  double microstep_um = 0.09921875;  // linear stage: 1/64 of a 6.35 um full step
  double microstep_deg = 0.000234375;  // rotary stage
  double travel_mm = 2500.0, travel_deg = 360.0;
  double maxspeed_mm_s = 250.0, accel_mm_s2 = 1000.0;
  double maxspeed_deg_s = 60.0, accel_deg_s2 = 240.0;
  double power_on_mm = 1000.0, power_on_deg = 0.0;  // where the stage rests at power-up
  bool comm_checksum = false;  // `comm.checksum` as found at start (non-volatile)
  double reset_s = 0.0;        // a power cycle's boot: deaf and silent this long (simulated s)
  bool power_up_alert = false;  // at the boot's end each device sends "!dd 0 IDLE WR" (an alert)
};

struct ZaberAxis {
  std::string rig_axis;  // slide | pan | tilt
  int device = 1, number = 1;
  double unit_per_ustep = 1.0;  // mm or deg per microstep
  double origin = 0.0, direction = 1.0;
  // state
  double true_ustep = 0.0;    // physical position from the home sensor
  double offset_ustep = 0.0;  // true - reported (0 once homed)
  long limit_min = 0, limit_max = 0;
  double maxspeed_ustep_s = 1.0, accel_ustep_s2 = 1.0, power_on_ustep = 0.0;
  TrapezoidMove move;
  bool moving = false, homing = false, homed = false, stalled = false, stuck_move = false;
  double Reported() const { return true_ustep - offset_ustep; }
  double RigValue() const { return origin + direction * true_ustep * unit_per_ustep; }
};

struct ZaberCommand {
  int device = 0, axis = 0;
  int id = -1;              // message id, -1 when absent
  bool checksummed = false;
  bool checksum_ok = true;
  std::vector<std::string> words;
};

std::string Hex2(unsigned value) {
  char text[3];
  std::snprintf(text, sizeof(text), "%02X", value & 0xFFu);
  return text;
}

unsigned Checksum(const std::string& body) {
  unsigned sum = 0;
  for (unsigned char c : body) sum += c;
  return (256u - (sum & 0xFFu)) & 0xFFu;
}

bool IsNumber(const std::string& word) {
  if (word.empty()) return false;
  std::size_t i = (word[0] == '-' || word[0] == '+') ? 1 : 0;
  if (i == word.size()) return false;
  for (; i < word.size(); ++i) {
    if (!std::isdigit(static_cast<unsigned char>(word[i]))) return false;
  }
  return true;
}

// Splits "/1 1 12 move abs 100:CC" into addresses, id, words and the checksum's verdict.
std::optional<ZaberCommand> ParseCommand(const std::string& message) {
  std::size_t start = message.find('/');
  if (start == std::string::npos) return std::nullopt;
  std::string body = message.substr(start + 1);
  ZaberCommand command;
  const std::size_t colon = body.find(':');
  if (colon != std::string::npos) {
    command.checksummed = true;
    const std::string given = body.substr(colon + 1);
    command.checksum_ok = given.size() >= 2 && given.substr(0, 2) == Hex2(Checksum(body.substr(0, colon)));
    body = body.substr(0, colon);
  }
  std::istringstream in(body);
  std::string word;
  std::vector<std::string> words;
  while (in >> word) words.push_back(word);
  std::size_t i = 0;
  if (i < words.size() && IsNumber(words[i])) command.device = std::stoi(words[i++]);
  if (i < words.size() && IsNumber(words[i])) command.axis = std::stoi(words[i++]);
  if (i < words.size() && IsNumber(words[i])) command.id = std::stoi(words[i++]);
  command.words.assign(words.begin() + static_cast<long>(i), words.end());
  return command;
}

class ZaberEmulator : public LineDevice {
 public:
  ZaberEmulator(World& world, const EmulatorSpec& spec, const DeviceKeys& keys,
                ZaberConfig config, std::vector<ZaberAxis> axes)
      : LineDevice(world, spec.name, keys.faults, spec.seed),
        config_(std::move(config)),
        axes_(std::move(axes)) {
    comm_checksum_ = config_.comm_checksum;
    SetReplyBitFlip(keys.flip);
    std::lock_guard<std::mutex> lock(state_mutex_);
    for (ZaberAxis& axis : axes_) axis.true_ustep = axis.power_on_ustep;
    ResetToPowerOn();
  }

  // The serving thread calls this class's hooks: stop it before the members go.
  ~ZaberEmulator() override { LineDevice::Stop(); }

 protected:
  std::string Terminators() const override { return "\r\n"; }
  std::string HandleMessage(const std::string& message) override;
  void Advance(double now_s) override;
  void ResetToPowerOn() override;
  double BootSeconds() const override { return config_.reset_s; }
  std::string BootMessage() override;

 private:
  struct Outcome {
    bool ok = true;
    std::string data = "0";
  };
  std::string ReplyOfDevice(const ZaberCommand& command, int device);
  Outcome Execute(const ZaberCommand& command, const std::vector<ZaberAxis*>& targets);
  Outcome Move(const std::vector<std::string>& words, const std::vector<ZaberAxis*>& targets);
  Outcome Get(const std::string& setting, int device, const std::vector<ZaberAxis*>& targets);
  Outcome Set(const std::vector<std::string>& words, const std::vector<ZaberAxis*>& targets);
  Outcome Warnings(const std::vector<std::string>& words, const std::vector<ZaberAxis*>& targets);
  void StartMove(ZaberAxis& axis, double target_reported_ustep);
  void Stop(ZaberAxis& axis, bool emergency);
  std::string Flag(const std::vector<ZaberAxis*>& targets) const;
  std::vector<ZaberAxis*> AxesOf(int device);

  ZaberConfig config_;
  std::vector<ZaberAxis> axes_;
  bool comm_checksum_ = false;  // replies carry a checksum
};

void ZaberEmulator::ResetToPowerOn() {
  // The stages stay where they are physically; the controller forgets its reference: it counts
  // from 0 at the current place and raises WR until homed. Settings return to their defaults.
  for (ZaberAxis& axis : axes_) {
    axis.offset_ustep = axis.true_ustep;
    axis.move = TrapezoidMove();
    axis.moving = axis.homing = axis.homed = axis.stalled = axis.stuck_move = false;
  }
  Advance(Now());
}

// Manual, "Alerts": an unsolicited message "!dd a status warning" (a checksum while comm.checksum
// is 1). A controller booting after a power cut may send one, the reference lost (WR).
std::string ZaberEmulator::BootMessage() {
  if (!config_.power_up_alert) return "";
  std::set<int> devices;
  for (const ZaberAxis& axis : axes_) devices.insert(axis.device);
  std::string alerts;
  for (int device : devices) {
    const std::string body = std::string(device < 10 ? "0" : "") + std::to_string(device) +
                             " 0 IDLE WR";
    alerts += "!" + body + (comm_checksum_ ? ":" + Hex2(Checksum(body)) : "") + "\r\n";
  }
  return alerts;
}

void ZaberEmulator::Advance(double now_s) {
  std::map<std::string, double> rig;
  bool any_moving = false;
  for (ZaberAxis& axis : axes_) {
    if (axis.moving) {
      if (!axis.stuck_move) axis.true_ustep = axis.move.Position(now_s);
      if (axis.move.Done(now_s)) {
        axis.moving = false;
        if (axis.stuck_move) axis.stalled = true;  // FS: the move ended away from its target
        if (axis.homing && !axis.stuck_move) axis.homed = true;
        axis.homing = false;
      }
    }
    any_moving = any_moving || axis.moving;
    rig[axis.rig_axis] = axis.RigValue();
  }
  WriteWorldAxes(world(), this, rig, any_moving);
}

std::vector<ZaberAxis*> ZaberEmulator::AxesOf(int device) {
  std::vector<ZaberAxis*> found;
  for (ZaberAxis& axis : axes_) {
    if (axis.device == device) found.push_back(&axis);
  }
  return found;
}

std::string ZaberEmulator::HandleMessage(const std::string& message) {
  const std::optional<ZaberCommand> command = ParseCommand(message);
  if (!command) return "";  // not a command: the device ignores it
  std::set<int> devices;
  for (const ZaberAxis& axis : axes_) {
    if (command->device == 0 || command->device == axis.device) devices.insert(axis.device);
  }
  std::string replies;
  for (int device : devices) replies += ReplyOfDevice(*command, device);
  return replies;
}

std::string ZaberEmulator::Flag(const std::vector<ZaberAxis*>& targets) const {
  bool stalled = false, unreferenced = false;
  for (const ZaberAxis* axis : targets) {
    stalled = stalled || axis->stalled;
    unreferenced = unreferenced || !axis->homed;
  }
  return stalled ? "FS" : unreferenced ? "WR" : "--";  // faults before warnings
}

std::string ZaberEmulator::ReplyOfDevice(const ZaberCommand& command, int device) {
  std::vector<ZaberAxis*> targets = AxesOf(device);
  Outcome outcome;
  if (!command.checksum_ok) {
    outcome = {false, "BADDATA"};
  } else {
    if (command.axis > 0) {
      std::vector<ZaberAxis*> addressed;
      for (ZaberAxis* axis : targets) {
        if (axis->number == command.axis) addressed.push_back(axis);
      }
      targets = addressed;
    }
    outcome = targets.empty() ? Outcome{false, "BADAXIS"} : Execute(command, targets);
  }
  const std::vector<ZaberAxis*> all = AxesOf(device);
  bool busy = false;
  for (const ZaberAxis* axis : all) busy = busy || axis->moving;
  std::ostringstream body;
  body << (device < 10 ? "0" : "") << device << ' ' << command.axis;
  if (command.id >= 0) body << ' ' << command.id;
  body << ' ' << (outcome.ok ? "OK" : "RJ") << ' ' << (busy ? "BUSY" : "IDLE") << ' '
       << Flag(command.axis > 0 && !targets.empty() ? targets : all) << ' ' << outcome.data;
  std::string reply = "@" + body.str();
  if (comm_checksum_) reply += ":" + Hex2(Checksum(body.str()));
  return reply + "\r\n";
}

ZaberEmulator::Outcome ZaberEmulator::Execute(const ZaberCommand& command,
                                              const std::vector<ZaberAxis*>& targets) {
  const std::vector<std::string>& words = command.words;
  if (words.empty()) return {};
  const std::string& verb = words[0];
  if (verb == "home" && words.size() == 1) {
    for (ZaberAxis* axis : targets) {
      axis->offset_ustep = 0.0;  // the home sensor becomes the reference once reached
      axis->homed = false;
      StartMove(*axis, 0.0);
      axis->homing = true;
    }
    return {};
  }
  if (verb == "move") return Move(words, targets);
  if ((verb == "stop" || verb == "estop") && words.size() == 1) {
    for (ZaberAxis* axis : targets) Stop(*axis, verb == "estop");
    return {};
  }
  if (verb == "get" && words.size() == 2) return Get(words[1], targets.front()->device, targets);
  if (verb == "set") return Set(words, targets);
  if (verb == "warnings") return Warnings(words, targets);
  return {false, "BADCOMMAND"};
}

ZaberEmulator::Outcome ZaberEmulator::Move(const std::vector<std::string>& words,
                                           const std::vector<ZaberAxis*>& targets) {
  if (words.size() < 2) return {false, "BADCOMMAND"};
  const std::string& kind = words[1];
  const bool with_data = kind == "abs" || kind == "rel";
  if (!with_data && kind != "min" && kind != "max") return {false, "BADCOMMAND"};
  if (with_data && (words.size() != 3 || !IsNumber(words[2]))) return {false, "BADDATA"};
  if (!with_data && words.size() != 2) return {false, "BADDATA"};
  const double data = with_data ? std::stod(words[2]) : 0.0;
  for (const ZaberAxis* axis : targets) {
    const double target = kind == "abs" ? data
                          : kind == "rel" ? axis->Reported() + data
                          : kind == "min" ? axis->limit_min
                                          : axis->limit_max;
    if (target < axis->limit_min || target > axis->limit_max) return {false, "BADDATA"};
  }
  for (ZaberAxis* axis : targets) {
    const double target = kind == "abs" ? data
                          : kind == "rel" ? axis->Reported() + data
                          : kind == "min" ? axis->limit_min
                                          : axis->limit_max;
    StartMove(*axis, target);
  }
  return {};
}

void ZaberEmulator::StartMove(ZaberAxis& axis, double target_reported_ustep) {
  const double now_s = Now();
  axis.stalled = false;
  axis.homing = false;
  axis.stuck_move = Faults().stuck_axis == axis.rig_axis;
  axis.move = TrapezoidMove(axis.true_ustep, target_reported_ustep + axis.offset_ustep, now_s,
                            axis.maxspeed_ustep_s, axis.accel_ustep_s2);
  axis.moving = true;
  NoteMoveStarted();
}

void ZaberEmulator::Stop(ZaberAxis& axis, bool emergency) {
  if (!axis.moving) return;
  const double now_s = Now();
  axis.homing = false;
  if (emergency || axis.stuck_move) {
    axis.move = TrapezoidMove();
    axis.moving = false;
    return;
  }
  // Decelerate at the axis's acceleration from the present speed.
  const double velocity = axis.move.Velocity(now_s);
  const double stopping = velocity * velocity / (2.0 * axis.accel_ustep_s2);
  const double target = axis.true_ustep + (velocity >= 0 ? stopping : -stopping);
  axis.move = TrapezoidMove(axis.true_ustep, std::round(target), now_s,
                            std::max(std::fabs(velocity), 1.0), axis.accel_ustep_s2);
}

ZaberEmulator::Outcome ZaberEmulator::Get(const std::string& setting, int device,
                                          const std::vector<ZaberAxis*>& targets) {
  if (device == 0 && !targets.empty()) device = targets.front()->device;
  std::ostringstream data;
  if (setting == "deviceid") return {true, std::to_string(config_.device_id)};
  if (setting == "system.serial") return {true, std::to_string(config_.serial)};
  if (setting == "version") return {true, config_.version};
  if (setting == "system.axiscount") {
    int count = 0;
    for (const ZaberAxis* axis : AxesOf(device)) count = std::max(count, axis->number);
    return {true, std::to_string(count)};
  }
  if (setting == "comm.alert") return {true, "0"};
  if (setting == "comm.checksum") return {true, comm_checksum_ ? "1" : "0"};
  for (std::size_t i = 0; i < targets.size(); ++i) {
    const ZaberAxis& axis = *targets[i];
    if (i > 0) data << ' ';
    if (setting == "pos") {
      data << std::llround(axis.Reported());
    } else if (setting == "resolution") {
      data << config_.resolution;
    } else if (setting == "maxspeed") {
      data << std::llround(axis.maxspeed_ustep_s * kSpeedDataPerUstepS);
    } else if (setting == "accel") {
      data << std::llround(axis.accel_ustep_s2 * kAccelDataPerUstepS2);
    } else if (setting == "limit.max") {
      data << axis.limit_max;
    } else if (setting == "limit.min") {
      data << axis.limit_min;
    } else {
      return {false, "BADCOMMAND"};
    }
  }
  return {true, data.str()};
}

ZaberEmulator::Outcome ZaberEmulator::Set(const std::vector<std::string>& words,
                                          const std::vector<ZaberAxis*>& targets) {
  if (words.size() != 3) return {false, "BADDATA"};
  const std::string& setting = words[1];
  if (setting == "comm.alert") return {words[2] == "0", words[2] == "0" ? "0" : "BADDATA"};
  if (setting == "comm.checksum") {
    if (words[2] != "0" && words[2] != "1") return {false, "BADDATA"};
    comm_checksum_ = words[2] == "1";  // this reply already follows the new setting
    return {};
  }
  if (setting != "maxspeed" && setting != "accel" && setting != "limit.max" &&
      setting != "limit.min") {
    return {false, "BADCOMMAND"};
  }
  if (!IsNumber(words[2])) return {false, "BADDATA"};
  const long value = std::stol(words[2]);
  if ((setting == "maxspeed" || setting == "accel") && value <= 0) return {false, "BADDATA"};
  for (ZaberAxis* axis : targets) {
    if (setting == "maxspeed") axis->maxspeed_ustep_s = value / kSpeedDataPerUstepS;
    if (setting == "accel") axis->accel_ustep_s2 = value / kAccelDataPerUstepS2;
    if (setting == "limit.max") axis->limit_max = value;
    if (setting == "limit.min") axis->limit_min = value;
  }
  return {};
}

ZaberEmulator::Outcome ZaberEmulator::Warnings(const std::vector<std::string>& words,
                                               const std::vector<ZaberAxis*>& targets) {
  if (words.size() > 2 || (words.size() == 2 && words[1] != "clear")) return {false, "BADCOMMAND"};
  std::vector<std::string> flags;
  bool stalled = false, unreferenced = false;
  for (const ZaberAxis* axis : targets) {
    stalled = stalled || axis->stalled;
    unreferenced = unreferenced || !axis->homed;
  }
  if (stalled) flags.push_back("FS");
  if (unreferenced) flags.push_back("WR");
  std::ostringstream data;
  data << (flags.size() < 10 ? "0" : "") << flags.size();
  for (const std::string& flag : flags) data << ' ' << flag;
  if (words.size() == 2) {
    for (ZaberAxis* axis : targets) axis->stalled = false;  // WR stays until homed
  }
  return {true, data.str()};
}

// ----------------------------------------------------------------------------------------------
// Construction from the rig file.

const std::vector<std::string> kZaberKeys = {
    "device_id",     "serial",        "version",        "resolution",  "microstep_um",
    "microstep_deg", "travel_mm",     "travel_deg",     "maxspeed_mm_s", "accel_mm_s2",
    "maxspeed_deg_s", "accel_deg_s2", "power_on_mm",    "power_on_deg", "comm_checksum",
    "reset_s",       "power_up_alert"};

ZaberConfig ReadZaberConfig(const DeviceKeys& keys) {
  ZaberConfig c;
  c.device_id = static_cast<int>(keys.Number("device_id", c.device_id));
  c.serial = static_cast<long>(keys.Number("serial", static_cast<double>(c.serial)));
  c.version = keys.Text("version", c.version);
  c.resolution = static_cast<int>(keys.Number("resolution", c.resolution));
  c.microstep_um = keys.Number("microstep_um", c.microstep_um);
  c.microstep_deg = keys.Number("microstep_deg", c.microstep_deg);
  c.travel_mm = keys.Number("travel_mm", c.travel_mm);
  c.travel_deg = keys.Number("travel_deg", c.travel_deg);
  c.maxspeed_mm_s = keys.Number("maxspeed_mm_s", c.maxspeed_mm_s);
  c.accel_mm_s2 = keys.Number("accel_mm_s2", c.accel_mm_s2);
  c.maxspeed_deg_s = keys.Number("maxspeed_deg_s", c.maxspeed_deg_s);
  c.accel_deg_s2 = keys.Number("accel_deg_s2", c.accel_deg_s2);
  c.power_on_mm = keys.Number("power_on_mm", c.power_on_mm);
  c.power_on_deg = keys.Number("power_on_deg", c.power_on_deg);
  c.comm_checksum = keys.Boolean("comm_checksum", c.comm_checksum);
  c.reset_s = keys.Number("reset_s", c.reset_s);
  if (!(c.reset_s >= 0.0 && c.reset_s <= 86400.0)) keys.Fail("reset_s", "must be in [0, 86400] s");
  c.power_up_alert = keys.Boolean("power_up_alert", c.power_up_alert);
  for (const char* key : {"microstep_um", "microstep_deg", "travel_mm", "travel_deg",
                          "maxspeed_mm_s", "accel_mm_s2", "maxspeed_deg_s", "accel_deg_s2",
                          "resolution"}) {
    if (!(keys.Number(key, 1.0) > 0.0)) keys.Fail(key, "must be > 0");
  }
  return c;
}

ZaberAxis MakeAxis(const std::string& rig_axis, const std::string& address,
                   const ZaberConfig& c, const DeviceKeys& keys) {
  ZaberAxis axis;
  axis.rig_axis = rig_axis;
  std::istringstream in(address);
  if (!(in >> axis.device >> axis.number) || axis.device < 1 || axis.device > 99 ||
      axis.number < 1 || axis.number > 9) {
    keys.Fail("axes", "station.devices axes." + rig_axis + " must be \"<device 1-99> <axis 1-9>\"" +
                          ", not \"" + address + "\"");
  }
  const bool linear = rig_axis == "slide";
  const auto station = [&keys](const char* key, double fallback) {
    const auto it = keys.station_numbers.find(key);
    return it == keys.station_numbers.end() ? fallback : it->second;
  };
  axis.unit_per_ustep = linear ? c.microstep_um / 1000.0 : c.microstep_deg;
  axis.origin = station(linear ? "origin_mm" : "origin_deg", 0.0);
  axis.direction = station("direction", 1.0) < 0 ? -1.0 : 1.0;
  const double travel = linear ? c.travel_mm : c.travel_deg;
  axis.limit_max = std::lround(travel / axis.unit_per_ustep);
  axis.maxspeed_ustep_s = (linear ? c.maxspeed_mm_s : c.maxspeed_deg_s) / axis.unit_per_ustep;
  axis.accel_ustep_s2 = (linear ? c.accel_mm_s2 : c.accel_deg_s2) / axis.unit_per_ustep;
  const double power_on = linear ? c.power_on_mm : c.power_on_deg;
  axis.power_on_ustep = std::round((power_on - axis.origin) / (axis.direction * axis.unit_per_ustep));
  return axis;
}

std::unique_ptr<DeviceEmulator> CreateZaber(World& world, const EmulatorSpec& spec) {
  const DeviceKeys keys = ReadDeviceKeys(spec, kZaberKeys);
  const ZaberConfig config = ReadZaberConfig(keys);
  std::vector<ZaberAxis> axes;
  for (const auto& [rig_axis, address] : keys.axes) {
    if (!IsRigAxis(rig_axis)) keys.Fail("axes", "unknown rig axis '" + rig_axis + "'");
    axes.push_back(MakeAxis(rig_axis, address, config, keys));
  }
  if (axes.empty()) keys.Fail("axes", "station.devices." + spec.name + ".axes maps no axis");
  return std::make_unique<ZaberEmulator>(world, spec, keys, config, std::move(axes));
}

}  // namespace

IRDIST_REGISTER_EMULATOR(zaber_ascii, (EmulatorInfo{"zaber_ascii", &CreateZaber}));

}  // namespace irdist::sim
