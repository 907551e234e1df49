#pragma once
// Sweep plans: a sweep's spec (station/sweep_spec.h) expanded into the ordered list of station
// poses, the bracket of frames taken at each pose, and an estimate of how long the sweep takes (motion with a trapezoidal
// profile per axis, settle, exposure, readout, IRED current settle) beside its physical bound
// (the moves with the axes' own settle, the exposures and the readout: what no software can save)
// (moves + exposures + readout, no settle and no overhead).
//
// Plain data only: no Asio, no yaml-cpp. The station's sweep consumes the Pose list.

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "station/motion.h"
#include "station/pose.h"
#include "station/sweep_spec.h"

namespace irdist {

// One motion axis of the station: trapezoidal velocity profile.
struct AxisMotion {
  double speed = 1.0;         // cruise speed, unit/s (mm/s or deg/s), > 0
  double acceleration = 1.0;  // acceleration and deceleration, unit/s^2, > 0
  double settle_ms = 0.0;     // station-side settle after the profile ends, ms
  double home = 0.0;          // where homing leaves the axis: the sweep's first move starts there
};

// Timing model of a rig, used for the duration estimate. Defaults match the virtual rig's station
// emulator (sim/station_emulator.h) and a 1280x1024 Mono12 frame over Gigabit Ethernet.
struct MotionModel {
  AxisMotion slide{200.0, 400.0, 100.0, 1000.0};  // mm/s, mm/s^2, ms, mm
  AxisMotion pan{30.0, 60.0, 50.0};       // deg/s, deg/s^2, ms
  AxisMotion tilt{30.0, 60.0, 50.0};      // deg/s, deg/s^2, ms
  bool axes_move_together = true;  // true: a move lasts as long as its slowest axis; false: sum
  double readout_ms = 25.0;        // sensor readout and transfer of one frame, ms
  double frame_overhead_ms = 5.0;  // per frame: exposure change, trigger round trip, ms
  double pose_overhead_ms = 20.0;  // per pose: commands and position polling, ms
  bool IsValid(std::string* why) const;
};

// Duration of a trapezoidal (or, for short moves, triangular) profile covering `distance`, in s.
double TrapezoidMoveS(double distance, const AxisMotion& motion);

// A station pose of the plan: Pose, station/pose.h. The spec it is made of: station/sweep_spec.h.

// Axis order chosen by cost of one step (trapezoid time of the median step plus settles; the
// current's settle for the bias), most expensive outermost; single-valued axes after them;
// per-pose random axes innermost.
std::vector<SweepAxis> ChooseAxisOrder(const SweepSpec& spec, const MotionModel& motion);

struct PlanSummary {
  std::vector<std::string> order;  // axis names, outermost first
  std::vector<int> axis_counts;    // values per axis, in `order`
  int repeats = 1;
  int pose_count = 0;  // including repeats
  int frames_per_pose = 0;
  int frame_count = 0;
  int difference_count = 0;  // (t_n, t_r) pairs
  int moves = 0;             // pose changes that move at least one axis
  int current_changes = 0;   // including switching the IRED on for the first pose
  // Duration estimate, s. Homing before the sweep is not included.
  double motion_s = 0.0;          // trapezoidal profiles
  double station_settle_s = 0.0;  // MotionModel settle of the moved axes
  double move_settle_s = 0.0;     // SettleSpec::after_move_ms
  double current_settle_s = 0.0;  // what is left of after_current_ms once the move is done
  double exposure_s = 0.0;
  double readout_s = 0.0;
  double overhead_s = 0.0;        // per-frame and per-pose overhead
  double total_s = 0.0;           // sum of the above
  double physical_bound_s = 0.0;  // motion and the axes' own settle + exposure + readout
  std::string BriefReport() const;
};

struct Plan {
  std::vector<Pose> poses;
  std::vector<PlannedExposure> bracket;
  PlanSummary summary;
};

// Expands the spec. Throws CheckError when !spec.IsValid() or !motion.IsValid(), when a theta
// cannot be reached with the given tilt (|cos theta| > |cos tilt|), or when the plan would hold
// more than kMaxPlanFrames frames.
Plan MakePlan(const SweepSpec& spec, const MotionModel& motion);

// `model` with each axis's speed, acceleration, settle and home as its device reports them
// (Station::Speeds(), read from the devices once connected and homed): the plan of a composed rig
// on what its devices are actually set to. Axes absent from `speeds` keep the model's values.
MotionModel WithDeviceSpeeds(MotionModel model, const std::map<Axis, AxisSpeed>& speeds);

// "1h 02m 03s", "4m 05.2s", "12.3 s"; "over 1e9 s" for longer (or infinite) durations.
std::string FormatDuration(double seconds);

}  // namespace irdist
