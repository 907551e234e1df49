#pragma once
// The motion role: the slide and the pan-tilt head, driven by one controller for every axis (the
// irdist station) or by one controller per axis or group (a Zaber slide + a FLIR PTU head).
// station/station.h composes the role's devices; the sweep only talks to the composition.

#include <chrono>
#include <string>
#include <vector>

#include "station/device.h"

namespace irdist {

enum class Axis { kSlide, kPan, kTilt };
const char* AxisName(Axis axis);  // "slide", "pan", "tilt" (rig-file spelling)

// A pose of the three axes: the slide in mm from the camera, pan and tilt in degrees.
struct StationPosition {
  double slide_mm = 0.0;
  double pan_deg = 0.0;
  double tilt_deg = 0.0;
};

// One axis's motion, as the driver read it from the device (or the rig file's override), for the
// plan's duration estimate: trapezoidal profile plus the device's own settle.
struct AxisSpeed {
  double speed = 1.0;         // unit/s (mm/s, deg/s)
  double acceleration = 1.0;  // unit/s^2
  double settle_ms = 0.0;     // after the profile ends, before the device reports settled
  double home = 0.0;          // where homing leaves the axis
};

enum class MotionState { kUnhomed, kHoming, kIdle, kMoving, kEStop, kFault };
const char* MotionStateName(MotionState state);

class Motion {
 public:
  virtual ~Motion() = default;
  // Asks the device who it is and checks it is the kind the rig file names (a wrong device on the
  // port is a DeviceError before anything moves). Reads what the driver needs (resolution, limits).
  virtual DeviceIdentity Identify() = 0;
  // The axes this device drives (from the rig file's mapping).
  virtual std::vector<Axis> Axes() const = 0;
  virtual MotionState State() = 0;
  // Homes this device's axes and returns once they are settled at home. Throws DeviceError.
  virtual void Home() = 0;
  // Commands an absolute move of this device's axes (other axes of `target` are ignored) and
  // returns at once; WaitSettled() waits for it. Several devices' moves thus overlap.
  virtual void StartMove(const StationPosition& target) = 0;
  // Polls until every axis of this device is idle within tolerance of the last target. Throws
  // DeviceError (limit, fault, e-stop, an axis that does not arrive by `timeout`),
  // DeviceRestarted, LinkError.
  virtual void WaitSettled(std::chrono::milliseconds timeout) = 0;
  // Positions of this device's axes (others left as in `*position`).
  virtual void ReadPosition(StationPosition* position) = 0;
  // Controlled stop; returns when the axes stand still. Best effort: never throws.
  virtual void Stop() noexcept = 0;
  virtual AxisSpeed Speed(Axis axis) const = 0;
  // Sets `axis`'s cruise speed (unit/s: mm/s, deg/s) for the moves that follow, as the device's
  // protocol sets it (Zaber ASCII `set maxspeed`, the FLIR PTU's PS/TS, the irdist station's
  // SPEED); Speed() then reports it. Throws DeviceError (or StationError) when the device refuses
  // it (outside its speed bounds), LinkError. A power cycle restores the device's own speed.
  virtual void SetSpeed(Axis axis, double unit_per_s) = 0;
  // Throws DeviceRestarted when the device lost its state since Identify()/Home() (power cycle),
  // DeviceError when it is in e-stop or fault. Cheap: one exchange.
  virtual void CheckAlive() = 0;
};

}  // namespace irdist
