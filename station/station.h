#pragma once
// The station composed of devices: the rig file's `station:` section names, for each role, the
// devices that fill it (roles.motion: one or more devices, each driving the axes it maps;
// roles.source: one device; roles.trigger: a device, or the camera's own software trigger, which
// app/ builds and hands in). Station opens every device's serial port, builds its driver through
// the registry (station/driver.h), identifies every device before anything moves, and offers the
// sweep one station: moves of all motion devices together, the IRED current, the trigger, a
// liveness check of every device, and the IRED off on every exit path (the destructor too).
//
// Logging: one LineLog for every device. A station of one device logs its lines as they are
// (docs/station-protocol.md's log); with several devices each line is prefixed by the device's
// name ("slide: > /1 1 move abs 1000").

#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "station/driver.h"
#include "station/line_log.h"

namespace irdist {

// The rig file's `station:` composition (app/inputs/rig.cc fills it; a single-box rig, one irdist
// station box, becomes one irdist_station device named "station" filling every role).
struct StationSpec {
  std::vector<DeviceSpec> devices;
  std::vector<std::string> motion;  // device names, each driving the axes it maps
  std::string source;               // device name
  std::string trigger;              // device name, or kCameraSoftwareTrigger
  double current_tolerance_ma = 5.0;  // |measured - set| above this stops a run
  const DeviceSpec* Find(const std::string& name) const;
};

constexpr const char* kCameraSoftwareTrigger = "camera_software";

// The roles of `spec` against its devices' drivers, before anything is opened: throws InputError
// naming the rig file and the device's line when a role names no device or a device whose
// driver cannot fill it (DriverInfo::roles), or when an axis is driven by other than exactly one
// motion device (a device's axes are its `axes:` map; none: all three, the irdist station).
void CheckStationRoles(const StationSpec& spec);

struct StationOptions {
  // Device name -> port, overriding DeviceSpec::port (the virtual rig's ptys, `--port NAME=PATH`).
  std::map<std::string, std::string> ports;
  LineLog* log = nullptr;  // must outlive the station
  // The trigger when StationSpec::trigger is camera_software (built by app/ over the camera);
  // may also be handed in later with Station::SetCameraTrigger().
  Trigger* camera_trigger = nullptr;
  std::chrono::milliseconds move_timeout{300000};
  // The destructor switches the IRED off (every run). `irdist station current` leaves it on:
  // false also keeps the source's output as it is found (CurrentSource::KeepOutput()).
  bool off_at_exit = true;
  // The first problem, naming the field, in *why (empty when valid).
  bool IsValid(std::string* why) const;
};

// The measured IRED current differs from its set-point by more than the tolerance (an open
// IRED, a source in compliance, a tripped output).
class CurrentMismatchError : public Error {
 public:
  using Error::Error;
};

// The station cannot start or continue: a motion device in e-stop, moving, or in fault.
class StationNotReadyError : public Error {
 public:
  using Error::Error;
};

class Station {
 public:
  // Opens every device's port and builds its driver; nothing is sent yet. Throws LinkError (a
  // port that cannot be opened), InputError (an unknown driver, a role naming no device).
  Station(const StationSpec& spec, StationOptions options);
  ~Station();  // switches the IRED off (best effort) unless options.off_at_exit is false
  Station(const Station&) = delete;
  Station& operator=(const Station&) = delete;

  // Identifies every device once (a wrong device on a port is a DeviceError before anything
  // moves) and checks that every axis has exactly one motion device.
  const std::vector<DeviceIdentity>& Identify();
  // "slide: zaber_ascii on /dev/pts/3: Zaber X-LSM ...; head: ..." (after Identify()).
  std::string IdentityBrief() const;
  // A clear StationNotReadyError when a motion device is in e-stop, fault, or still moving.
  void CheckReadyToStart();
  // Each motion device's state, by device name (irdist station status).
  std::vector<std::pair<std::string, MotionState>> States();

  void Home();  // every motion device, together
  bool homed() const { return homed_; }
  // StartMove on every motion device, then WaitSettled on each: the devices move together.
  void MoveTo(const StationPosition& target);
  // MoveTo that gives up when `stop()` turns true while an axis moves: every motion device is
  // stopped (Stop()) and false returned, the axes wherever they came to rest. A long profile's
  // move thus ends at a Ctrl-C at once. Throws as MoveTo.
  bool MoveToUnless(const StationPosition& target, const std::function<bool()>& stop);
  StationPosition Position();

  void SetCurrent(double bias_ma);
  double setpoint_ma() const;
  SourceReading MeasureCurrent();
  // Throws CurrentMismatchError when `reading` is off the set-point by more than the tolerance,
  // or in compliance.
  void CheckCurrent(const SourceReading& reading) const;
  // One measurement, checked: on a mismatch every device is checked alive first (a device that
  // restarted lost its current: DeviceRestarted, the pose is retaken), then CurrentMismatchError.
  SourceReading MeasureCheckedCurrent();

  // camera_software: the camera's trigger, once the camera is open (must outlive the station's
  // use of it).
  void SetCameraTrigger(Trigger* trigger);
  void Fire(int frame_in_bracket);
  const char* TriggerCameraSource() const;  // "Line1", "Software"

  // CheckAlive on every device (DeviceRestarted, DeviceError for e-stop / tripped output).
  void CheckAlive();
  void Off() noexcept;   // the IRED off, best effort
  void Stop() noexcept;  // every motion device stopped, best effort

  // Each axis's motion as its device reports it (for the plan's duration estimate).
  std::map<Axis, AxisSpeed> Speeds() const;
  // The cruise speed of `axis` (mm/s or deg/s) for the moves that follow, through the motion
  // device that drives it (Motion::SetSpeed). Throws DeviceError, StationError, LinkError.
  void SetSpeed(Axis axis, double unit_per_s);
  const StationSpec& spec() const { return spec_; }

 private:
  struct Device {
    std::string name;
    std::unique_ptr<DeviceDriver> driver;
    DeviceIdentity identity;
  };
  Device& Named(const std::string& name);
  // "station.devices.source (scpi_source on /dev/ttyUSB2: KEITHLEY ...)": errors of the source.
  std::string SourceBrief() const;
  void OpenDevice(const DeviceSpec& device);
  void BindRoles();

  StationSpec spec_;
  StationOptions options_;
  std::vector<Device> devices_;
  std::vector<Motion*> motion_;
  CurrentSource* source_ = nullptr;
  Trigger* trigger_ = nullptr;
  std::vector<DeviceIdentity> identities_;
  bool homed_ = false;
};

}  // namespace irdist
