#pragma once
// Station-internal (included by the drivers' .cc files only, never by a public header): the Motion
// plumbing of a driver whose axes are its rig-file entry's `axes:` (zaber_ascii, flir_ptu): the
// driver is its own motion role, its axis list answers Axes() and Speed(), and a pose's value of
// an axis is read and written in one place. What each driver does with its axes (identify, home,
// move, settle, stop, its reply syntax and its failures) stays in its own file.

#include <vector>

#include "station/driver.h"
#include "station/motion.h"

namespace irdist {

// The value of `axis` in `pose` (slide_mm, pan_deg or tilt_deg), to read or to set.
inline double AxisValue(const StationPosition& pose, Axis axis) {
  return axis == Axis::kSlide ? pose.slide_mm : axis == Axis::kPan ? pose.pan_deg : pose.tilt_deg;
}
inline void SetAxisValue(StationPosition* pose, Axis axis, double value) {
  double* field = axis == Axis::kSlide ? &pose->slide_mm
                  : axis == Axis::kPan ? &pose->pan_deg
                                       : &pose->tilt_deg;
  *field = value;
}

// A motion driver over a list of axes, each an `AxisState` with at least `Axis axis` and
// `AxisSpeed speed` (as the driver read it from the device).
template <typename AxisState>
class AxesMotionDriver : public DeviceDriver, public Motion {
 public:
  Motion* motion() override { return this; }
  std::vector<Axis> Axes() const override {
    std::vector<Axis> out;
    for (const AxisState& a : axes_) out.push_back(a.axis);
    return out;
  }
  AxisSpeed Speed(Axis axis) const override {
    for (const AxisState& a : axes_) {
      if (a.axis == axis) return a.speed;
    }
    return {};
  }

 protected:
  std::vector<AxisState> axes_;  // in the rig file's order
};

}  // namespace irdist
