#pragma once
// The one pose type, carried unchanged from the plan (station/plan.h) through the sweep
// (station/sweep.h) to the live recorder (app/runs/capture.h). The recording's row stays
// acquisition's own (acquisition/recording_types.h FrameRecord); app/runs/capture.cc fills its pose
// columns from a Pose in one place.

#include <cstdint>

namespace irdist {

// A station pose. theta_deg is the IRED orientation, cos(theta) = cos(pan) cos(tilt): as given in
// kTheta mode (pan carries its sign), acos(cos(pan) cos(tilt)) >= 0 in kPan mode.
struct Pose {
  std::int64_t index = 0;  // position in the plan, 0-based; the recording's bracket_id
  double slide_mm = 0.0;
  double pan_deg = 0.0;
  double tilt_deg = 0.0;
  double bias_ma = 0.0;    // IRED current at this pose (0 = off)
  double theta_deg = 0.0;
  int repeat = 0;          // 0 .. repeats-1: brackets repeated without moving
};

}  // namespace irdist
