// The motion role's names (station/motion.h): the rig file's axis spelling and the states' names
// the logs and errors print.
#include "station/motion.h"

#include <gtest/gtest.h>

#include <string>

namespace irdist {
namespace {

TEST(Motion, AxisNamesAreTheRigFilesSpelling) {
  EXPECT_EQ(std::string(AxisName(Axis::kSlide)), "slide");
  EXPECT_EQ(std::string(AxisName(Axis::kPan)), "pan");
  EXPECT_EQ(std::string(AxisName(Axis::kTilt)), "tilt");
  EXPECT_EQ(std::string(AxisName(static_cast<Axis>(7))), "?");
}

TEST(Motion, EveryStateHasItsOwnName) {
  EXPECT_EQ(std::string(MotionStateName(MotionState::kUnhomed)), "unhomed");
  EXPECT_EQ(std::string(MotionStateName(MotionState::kHoming)), "homing");
  EXPECT_EQ(std::string(MotionStateName(MotionState::kIdle)), "idle");
  EXPECT_EQ(std::string(MotionStateName(MotionState::kMoving)), "moving");
  EXPECT_EQ(std::string(MotionStateName(MotionState::kEStop)), "e-stop");
  EXPECT_EQ(std::string(MotionStateName(MotionState::kFault)), "fault");
  EXPECT_EQ(std::string(MotionStateName(static_cast<MotionState>(99))), "?");
}

}  // namespace
}  // namespace irdist
