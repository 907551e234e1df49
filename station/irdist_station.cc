#include "station/irdist_station.h"

#include "base/bounds.h"
#include "base/input_error.h"

namespace irdist {
namespace {

constexpr const char* kFix = "see docs/devices/irdist_station.md and docs/station-protocol.md";

ClientOptions OptionsOf(const DeviceSpec& spec) {
  ClientOptions options;
  if (spec.reply_timeout_ms > 0) {
    options.reply_timeout = std::chrono::milliseconds(spec.reply_timeout_ms);
  }
  options.move_timeout =
      std::chrono::milliseconds(static_cast<long long>(spec.Number("move_timeout_ms", 300000)));
  return options;
}

void ValidateSpec(const DeviceSpec& spec) {
  spec.CheckKnown({"trigger_width_us", "trigger_period_us", "move_timeout_ms"});
  const double width = spec.Number("trigger_width_us", 100.0);
  const double period = spec.Number("trigger_period_us", 1000.0);
  if (!(width >= 1.0 && period > width)) {
    throw InputError(spec.file, spec.line, 0,
                     "station.devices." + spec.name +
                         ": trigger_width_us must be >= 1 and below trigger_period_us");
  }
  const double move_timeout_ms = spec.Number("move_timeout_ms", 300000);
  if (!(move_timeout_ms >= 1.0 && bounds::kDelayMs.Contains(move_timeout_ms))) {
    throw InputError(spec.file, spec.line, 0,
                     "station.devices." + spec.name + ".move_timeout_ms must lie in [1, " +
                         BoundNumber(bounds::kDelayMs.max) + "] ms (" + bounds::kDelayMs.why +
                         "; cast to an integer count later)");
  }
  if (!spec.axes.empty() && spec.axes.size() != 3) {
    throw InputError(spec.file, spec.line, 0,
                     "station.devices." + spec.name +
                         ": an irdist_station drives the three axes; map slide, pan and tilt "
                         "(or omit axes:)");
  }
}

}  // namespace

IrdistStationDriver::IrdistStationDriver(const DeviceSpec& spec,
                                         std::unique_ptr<Transport> transport)
    : spec_(spec), transport_(std::move(transport)), client_(*transport_, OptionsOf(spec)) {
  identity_.kind = "irdist_station";
  identity_.port = spec.port;
  trigger_width_us_ = spec.Number("trigger_width_us", 100.0);
  trigger_period_us_ = spec.Number("trigger_period_us", 1000.0);
}

// StationError (a refusal, a failed move) becomes a DeviceError naming the device; reboots
// (StationRebooted, a DeviceRestarted) and link errors pass as they are.
template <typename F>
auto IrdistStationDriver::Guarded(F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const StationError& e) {
    throw DeviceError(identity_, e.code() == 0 ? "" : std::to_string(e.code()), e.what(), kFix);
  }
}

DeviceIdentity IrdistStationDriver::Identify() {
  for (double& speed : set_speed_) speed = 0.0;  // a new session: the station's own speeds
  const StationIdentity id = Guarded([&] { return client_.Identify(); });
  identity_.vendor = id.vendor;
  identity_.model = id.model;
  identity_.serial = id.serial;
  identity_.firmware = id.firmware + " boot " + id.boot_id;
  return identity_;
}

std::vector<Axis> IrdistStationDriver::Axes() const {
  return {Axis::kSlide, Axis::kPan, Axis::kTilt};
}

MotionState IrdistStationDriver::State() {
  switch (Guarded([&] { return client_.Status().state; })) {
    case StationState::kUnhomed:
      return MotionState::kUnhomed;
    case StationState::kHoming:
      return MotionState::kHoming;
    case StationState::kIdle:
      return MotionState::kIdle;
    case StationState::kMoving:
    case StationState::kSettling:
      return MotionState::kMoving;
    case StationState::kEStop:
      return MotionState::kEStop;
    case StationState::kUnknown:
      break;
  }
  return MotionState::kFault;
}

void IrdistStationDriver::Home() {
  Guarded([&] { client_.Home(); });
}

void IrdistStationDriver::StartMove(const StationPosition& target) {
  Guarded([&] { client_.StartMove(target); });
}

void IrdistStationDriver::WaitSettled(std::chrono::milliseconds) {
  // The client's own move timeout (move_timeout_ms) bounds the wait.
  Guarded([&] { client_.WaitMoveSettled(); });
}

void IrdistStationDriver::ReadPosition(StationPosition* position) {
  *position = Guarded([&] { return client_.Position(); });
}

void IrdistStationDriver::Stop() noexcept {
  try {
    client_.Stop();
  } catch (const std::exception&) {
    // Best effort: the caller is already on a failure path.
  }
}

AxisSpeed IrdistStationDriver::Speed(Axis axis) const {
  // The protocol has no speed query: the documented defaults of docs/station-protocol.md (the
  // emulator's); a rig file's `station.motion:` overrides them.
  AxisSpeed speed = axis == Axis::kSlide ? AxisSpeed{200.0, 400.0, 100.0, 1000.0}
                                          : AxisSpeed{30.0, 60.0, 50.0, 0.0};
  const double set = set_speed_[static_cast<int>(axis)];
  if (set > 0.0) speed.speed = set;
  return speed;
}

void IrdistStationDriver::SetSpeed(Axis axis, double unit_per_s) {
  const char* name = axis == Axis::kSlide ? "SLIDE" : axis == Axis::kPan ? "PAN" : "TILT";
  Guarded([&] { client_.SetSpeed(name, unit_per_s); });
  set_speed_[static_cast<int>(axis)] = unit_per_s;
}

void IrdistStationDriver::SetCurrent(double bias_ma) {
  Guarded([&] { client_.SetCurrent(bias_ma); });
}

SourceReading IrdistStationDriver::Measure() {
  SourceReading reading;
  reading.current_ma = Guarded([&] { return client_.MeasureCurrent(); });
  reading.output_on = client_.current_setpoint_ma() > 0.0;
  return reading;
}

void IrdistStationDriver::Off() noexcept {
  try {
    client_.SetCurrent(0.0);
  } catch (const std::exception&) {
    // Best effort; the station itself switches the IRED off when the link is lost.
  }
}

void IrdistStationDriver::CheckAlive() {
  const StationState state = Guarded([&] { return client_.Status().state; });
  if (state == StationState::kEStop) {
    throw DeviceError(identity_, "ESTOP", "the station is in emergency stop",
                      "release the emergency stop, clear it (ESTOP:CLR or 'irdist station "
                      "home') and resume the run");
  }
}

void IrdistStationDriver::Fire(int) {
  Guarded([&] {
    client_.Trigger(1, trigger_width_us_, trigger_period_us_);
    client_.WaitTriggerDone();
  });
  ++fired_;
}

DriverInfo IrdistStationInfo() {
  DriverInfo info;
  info.name = "irdist_station";
  info.line_end = "\r\n";
  info.default_baud = 115200;
  info.default_reply_timeout_ms = 500;
  info.roles = {"motion", "source", "trigger"};
  info.doc = "docs/devices/irdist_station.md";
  info.validate = ValidateSpec;
  info.create = [](const DeviceSpec& spec, std::unique_ptr<Transport> transport) {
    return std::unique_ptr<DeviceDriver>(new IrdistStationDriver(spec, std::move(transport)));
  };
  return info;
}

IRDIST_REGISTER_DRIVER(irdist_station, IrdistStationInfo());

}  // namespace irdist
