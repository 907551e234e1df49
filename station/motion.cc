#include "station/motion.h"

namespace irdist {

const char* AxisName(Axis axis) {
  switch (axis) {
    case Axis::kSlide:
      return "slide";
    case Axis::kPan:
      return "pan";
    case Axis::kTilt:
      return "tilt";
  }
  return "?";
}

const char* MotionStateName(MotionState state) {
  switch (state) {
    case MotionState::kUnhomed:
      return "unhomed";
    case MotionState::kHoming:
      return "homing";
    case MotionState::kIdle:
      return "idle";
    case MotionState::kMoving:
      return "moving";
    case MotionState::kEStop:
      return "e-stop";
    case MotionState::kFault:
      return "fault";
  }
  return "?";
}

}  // namespace irdist
