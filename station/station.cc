#include "station/station.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <future>
#include <set>
#include <thread>

#include "base/input_error.h"
#include "station/serial_transport.h"

namespace irdist {

const DeviceSpec* StationSpec::Find(const std::string& name) const {
  for (const DeviceSpec& d : devices) {
    if (d.name == name) return &d;
  }
  return nullptr;
}

namespace {

// The device's registered driver; an unknown one is an InputError at the device's line.
const DriverInfo& DriverOf(const DeviceSpec& device) {
  const DriverInfo* info = FindDriver(device.driver);
  if (info == nullptr) {
    std::string known;
    for (const std::string& n : DriverNames()) known += (known.empty() ? "" : ", ") + n;
    throw InputError(device.file, device.line, 0,
                     "station.devices." + device.name + ": unknown driver '" + device.driver +
                         "'; known drivers: " + known);
  }
  return *info;
}

std::string RigFileOf(const StationSpec& spec) {
  return spec.devices.empty() ? std::string("the rig file") : spec.devices.front().file;
}

bool CanFill(const DeviceSpec& device, const std::string& role) {
  const DriverInfo* info = FindDriver(device.driver);
  return info != nullptr &&
         std::find(info->roles.begin(), info->roles.end(), role) != info->roles.end();
}

// A role given to a device that cannot fill it: the device's line and the devices that can.
[[noreturn]] void ThrowCannotFill(const StationSpec& spec, const DeviceSpec& device,
                                  const std::string& role) {
  std::string able;
  for (const DeviceSpec& d : spec.devices) {
    if (CanFill(d, role)) able += (able.empty() ? "" : ", ") + d.name;
  }
  throw InputError(device.file, device.line, 0,
                   "station.roles." + role + " names device '" + device.name + "' (driver " +
                       device.driver + "), which cannot fill the " + role + " role; " +
                       (able.empty() ? "add a device whose driver can (docs/devices/)"
                                     : "name one that can: " + able));
}

const DeviceSpec& RoleDevice(const StationSpec& spec, const std::string& name,
                             const std::string& role) {
  const DeviceSpec* device = spec.Find(name);
  if (device == nullptr) {
    throw InputError(RigFileOf(spec), 0, 0,
                     "station.roles." + role + " names '" + name +
                         "', which is not in station.devices; name one of its devices");
  }
  if (!CanFill(*device, role)) ThrowCannotFill(spec, *device, role);
  return *device;
}

std::vector<Axis> DeclaredAxes(const DeviceSpec& device) {
  if (device.axes.empty()) return {Axis::kSlide, Axis::kPan, Axis::kTilt};
  std::vector<Axis> axes;
  for (const auto& entry : device.axes) axes.push_back(entry.first);
  return axes;
}

// Each axis driven by exactly one motion device; `drivers_of` lists the devices of each axis.
void CheckAxisDrivers(const StationSpec& spec,
                      const std::map<Axis, std::vector<std::string>>& drivers_of) {
  for (Axis axis : {Axis::kSlide, Axis::kPan, Axis::kTilt}) {
    const auto found = drivers_of.find(axis);
    const std::vector<std::string> names =
        found == drivers_of.end() ? std::vector<std::string>{} : found->second;
    if (names.size() == 1) continue;
    std::string list;
    for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
    const DeviceSpec* second = names.size() > 1 ? spec.Find(names[1]) : nullptr;
    throw InputError(RigFileOf(spec), second != nullptr ? second->line : 0, 0,
                     std::string("axis ") + AxisName(axis) + " is driven by " +
                         std::to_string(names.size()) + " motion devices" +
                         (list.empty() ? "" : " (" + list + ")") +
                         "; map each axis to exactly one device of station.roles.motion in its "
                         "station.devices.<name>.axes");
  }
}

}  // namespace

void CheckStationRoles(const StationSpec& spec) {
  for (const DeviceSpec& device : spec.devices) DriverOf(device);
  std::map<Axis, std::vector<std::string>> drivers_of;
  for (const std::string& name : spec.motion) {
    for (Axis axis : DeclaredAxes(RoleDevice(spec, name, "motion"))) {
      drivers_of[axis].push_back(name);
    }
  }
  RoleDevice(spec, spec.source, "source");
  if (spec.trigger != kCameraSoftwareTrigger) RoleDevice(spec, spec.trigger, "trigger");
  CheckAxisDrivers(spec, drivers_of);
}

bool StationOptions::IsValid(std::string* why) const {
  std::string reason;
  for (const auto& [name, path] : ports) {
    if (name.empty() || path.empty()) {
      reason = "ports: an entry without a device name or a path ('" + name + "=" + path + "')";
      break;
    }
  }
  if (reason.empty() && move_timeout <= std::chrono::milliseconds::zero()) {
    reason = "move_timeout not above 0 ms";
  }
  if (why != nullptr) *why = reason;
  return reason.empty();
}

Station::Station(const StationSpec& spec, StationOptions options)
    : spec_(spec), options_(std::move(options)) {
  std::string why;
  IRDIST_CHECK(options_.IsValid(&why), "StationOptions: " + why);
  CheckStationRoles(spec_);
  for (const DeviceSpec& device : spec_.devices) OpenDevice(device);
  BindRoles();
}

Station::~Station() {
  if (options_.off_at_exit) Off();
}

void Station::OpenDevice(const DeviceSpec& device) {
  const DriverInfo* info = &DriverOf(device);
  DeviceSpec opened = device;
  const auto port = options_.ports.find(device.name);
  if (port != options_.ports.end()) opened.port = port->second;
  if (opened.port == "auto") {
    throw InputError(device.file, device.line, 0,
                     "station.devices." + device.name +
                         ".port is 'auto', which only a virtual rig resolves; name the serial "
                         "device (e.g. /dev/ttyUSB0) or pass --port " + device.name + "=PATH");
  }
  if (opened.baud <= 0) opened.baud = static_cast<int>(info->default_baud);
  if (opened.reply_timeout_ms <= 0) opened.reply_timeout_ms = info->default_reply_timeout_ms;
  SerialOptions serial;
  serial.baud = static_cast<unsigned int>(opened.baud);
  serial.line_end = info->line_end;
  serial.cr_ends_line = info->cr_ends_reply;
  if (spec_.devices.size() > 1) serial.log_prefix = device.name + ": ";
  serial.origin = (port != options_.ports.end() ? "--port " + device.name + "=PATH or "
                                                : std::string()) +
                  device.file + (device.line > 0 ? ":" + std::to_string(device.line) : "") +
                  " (device '" + device.name + "': its port and baud)";
  auto transport = std::make_unique<SerialTransport>(opened.port, serial, options_.log);
  devices_.push_back({device.name, info->create(opened, std::move(transport)), {}});
}

Station::Device& Station::Named(const std::string& name) {
  for (Device& d : devices_) {
    if (d.name == name) return d;
  }
  throw InputError(spec_.devices.empty() ? "" : spec_.devices.front().file, 0, 0,
                   "station.roles names '" + name + "', which is not in station.devices");
}

void Station::BindRoles() {
  for (const std::string& name : spec_.motion) {
    Motion* motion = Named(name).driver->motion();
    if (motion == nullptr) ThrowCannotFill(spec_, *spec_.Find(name), "motion");
    motion_.push_back(motion);
  }
  source_ = Named(spec_.source).driver->source();
  if (source_ == nullptr) ThrowCannotFill(spec_, *spec_.Find(spec_.source), "source");
  if (!options_.off_at_exit) source_->KeepOutput();  // irdist station: found and left as is
  if (spec_.trigger == kCameraSoftwareTrigger) {
    trigger_ = options_.camera_trigger;  // or SetCameraTrigger() once the camera is open
  } else {
    trigger_ = Named(spec_.trigger).driver->trigger();
    if (trigger_ == nullptr) ThrowCannotFill(spec_, *spec_.Find(spec_.trigger), "trigger");
  }
}

const std::vector<DeviceIdentity>& Station::Identify() {
  identities_.clear();
  for (Device& d : devices_) {
    DeviceDriver& drv = *d.driver;
    if (drv.motion() != nullptr) {
      d.identity = drv.motion()->Identify();
    } else if (drv.source() != nullptr) {
      d.identity = drv.source()->Identify();
    } else if (drv.trigger() != nullptr) {
      d.identity = drv.trigger()->Identify();
    }
    identities_.push_back(d.identity);
  }
  std::map<Axis, std::vector<std::string>> drivers_of;
  for (std::size_t i = 0; i < motion_.size(); ++i) {
    for (Axis axis : motion_[i]->Axes()) drivers_of[axis].push_back(spec_.motion[i]);
  }
  CheckAxisDrivers(spec_, drivers_of);
  return identities_;
}

std::string Station::IdentityBrief() const {
  std::string out;
  for (const Device& d : devices_) {
    out += (out.empty() ? "" : "; ") + d.name + ": " + d.identity.Brief();
  }
  return out;
}

void Station::CheckReadyToStart() {
  bool all_idle = true;
  for (std::size_t i = 0; i < motion_.size(); ++i) {
    const MotionState state = motion_[i]->State();
    const std::string who = spec_.motion[i];
    if (state == MotionState::kEStop) {
      throw StationNotReadyError(
          "station device '" + who +
          "' is in emergency stop; release the stop button, clear it (irdist station home "
          "--rig RIG) and start again");
    }
    if (state == MotionState::kMoving || state == MotionState::kHoming) {
      throw StationNotReadyError("station device '" + who + "' is " + MotionStateName(state) +
                                 " (another program is driving it?); wait until it stands "
                                 "still, or stop it with 'irdist station off', and start again");
    }
    if (state == MotionState::kFault) {
      throw StationNotReadyError("station device '" + who +
                                 "' reports a fault; check it and home it (irdist station home)");
    }
    all_idle = all_idle && state == MotionState::kIdle;
  }
  // Idle means homed (an unhomed device says so); a sweep still homes first unless told not to.
  homed_ = all_idle;
}

std::vector<std::pair<std::string, MotionState>> Station::States() {
  std::vector<std::pair<std::string, MotionState>> states;
  for (std::size_t i = 0; i < motion_.size(); ++i) {
    states.emplace_back(spec_.motion[i], motion_[i]->State());
  }
  return states;
}

void Station::Home() {
  homed_ = false;
  for (Motion* m : motion_) m->Home();
  homed_ = true;
}

void Station::MoveTo(const StationPosition& target) {
  for (Motion* m : motion_) m->StartMove(target);
  for (Motion* m : motion_) m->WaitSettled(options_.move_timeout);
}

bool Station::MoveToUnless(const StationPosition& target, const std::function<bool()>& stop) {
  constexpr std::chrono::milliseconds kStopPoll{20};
  for (Motion* m : motion_) m->StartMove(target);
  for (Motion* m : motion_) {
    while (m->State() == MotionState::kMoving) {
      if (stop()) {
        Stop();
        return false;
      }
      std::this_thread::sleep_for(kStopPoll);
    }
  }
  for (Motion* m : motion_) m->WaitSettled(options_.move_timeout);
  return true;
}

StationPosition Station::Position() {
  StationPosition position;
  for (Motion* m : motion_) m->ReadPosition(&position);
  return position;
}

void Station::SetCurrent(double bias_ma) { source_->SetCurrent(bias_ma); }

double Station::setpoint_ma() const { return source_->setpoint_ma(); }

SourceReading Station::MeasureCurrent() { return source_->Measure(); }

void Station::CheckCurrent(const SourceReading& reading) const {
  const double set_ma = source_->setpoint_ma();
  const double off_ma = std::fabs(reading.current_ma - set_ma);
  if (off_ma <= spec_.current_tolerance_ma && !reading.in_compliance) return;
  char text[320];
  std::snprintf(text, sizeof(text),
                "IRED current measured %.2f mA where %.2f mA is set (tolerance %.2f mA%s): %s",
                reading.current_ma, set_ma, spec_.current_tolerance_ma,
                reading.in_compliance ? ", source in compliance" : "",
                reading.current_ma < 0.5 * set_ma
                    ? "the IRED circuit looks open, or the source's output tripped; check the "
                      "IRED's wiring and the source's compliance voltage, then resume the run"
                    : "the source cannot drive the set current; check the compliance voltage "
                      "and the IRED, then resume the run");
  throw CurrentMismatchError(SourceBrief() + ": " + text);
}

std::string Station::SourceBrief() const {
  for (const Device& d : devices_) {
    if (d.name == spec_.source) {
      return "station.devices." + d.name + " (" +
             (d.identity.kind.empty() ? spec_.Find(d.name)->driver : d.identity.Brief()) + ")";
    }
  }
  return "station.devices." + spec_.source;
}

void Station::SetCameraTrigger(Trigger* trigger) {
  IRDIST_CHECK(spec_.trigger == kCameraSoftwareTrigger, "the rig's trigger is ", spec_.trigger);
  trigger_ = trigger;
}

SourceReading Station::MeasureCheckedCurrent() {
  const SourceReading reading = MeasureCurrent();
  try {
    CheckCurrent(reading);
  } catch (const CurrentMismatchError&) {
    CheckAlive();
    throw;
  }
  return reading;
}

void Station::Fire(int frame_in_bracket) {
  IRDIST_CHECK(trigger_ != nullptr,
               "roles.trigger is camera_software but no camera trigger was handed in");
  trigger_->Fire(frame_in_bracket);
}

const char* Station::TriggerCameraSource() const {
  return spec_.trigger == kCameraSoftwareTrigger ? "Software" : trigger_->CameraSource();
}

void Station::CheckAlive() {
  const auto CheckDeviceAlive = [](Device& d) {
    if (d.driver->motion() != nullptr) {
      d.driver->motion()->CheckAlive();
    } else if (d.driver->source() != nullptr) {
      d.driver->source()->CheckAlive();
    }
  };
  if (devices_.size() == 1) return CheckDeviceAlive(devices_.front());
  // Each device answers on its own link (and logs through the locked LineLog): asked at once, the
  // check costs the slowest reply, not their sum. The first device's error (in rig order) wins.
  std::vector<std::future<void>> checks;
  for (Device& d : devices_) {
    checks.push_back(
        std::async(std::launch::async, [&d, &CheckDeviceAlive] { CheckDeviceAlive(d); }));
  }
  for (std::future<void>& check : checks) check.get();
}

void Station::Off() noexcept {
  if (source_ != nullptr) source_->Off();
}

void Station::Stop() noexcept {
  for (Motion* m : motion_) m->Stop();
}

void Station::SetSpeed(Axis axis, double unit_per_s) {
  for (Motion* m : motion_) {
    for (Axis a : m->Axes()) {
      if (a == axis) m->SetSpeed(axis, unit_per_s);
    }
  }
}

std::map<Axis, AxisSpeed> Station::Speeds() const {
  std::map<Axis, AxisSpeed> speeds;
  for (Motion* m : motion_) {
    for (Axis axis : m->Axes()) speeds[axis] = m->Speed(axis);
  }
  return speeds;
}

}  // namespace irdist
