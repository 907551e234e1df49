#pragma once
// Sweep plans: a recipe's axes expanded into the ordered list of station poses, the bracket of
// frames taken at each pose, and an estimate of how long the sweep takes (motion with a trapezoidal
// profile per axis, settle, exposure, readout, IRED current settle) beside its physical bound
// (the moves with the axes' own settle, the exposures and the readout: what no software can save)
// (moves + exposures + readout, no settle and no overhead).
//
// Plain data only: no Asio, no yaml-cpp. app/inputs/recipe.h fills a SweepSpec from a recipe file;
// the station's sweep consumes the Pose list.

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "station/motion.h"
#include "station/pose.h"

namespace irdist {

// The four swept quantities. kAngle is theta or pan, depending on SweepSpec::angle_mode.
enum class SweepAxis { kSlide, kAngle, kTilt, kBias };

// How the angle axis is given: as the IRED orientation theta (pan derived from theta and tilt
// through cos(theta) = cos(pan) cos(tilt)) or directly as the pan angle.
enum class AngleMode { kTheta, kPan };

// Name of an axis as written in recipes: "slide_mm", "theta_deg" or "pan_deg", "tilt_deg",
// "bias_ma".
std::string SweepAxisName(SweepAxis axis, AngleMode angle_mode);

// Normal random draws of an axis (e.g. the IRED bias current of Fig. 13). Values outside
// [min, max] are redrawn (a truncated normal), so every draw stays inside the rig's limits.
struct RandomDraws {
  double mean = 500.0;     // unit of the axis
  double sd = 50.0;        // standard deviation, unit of the axis, >= 0
  int count = 10;          // draws per set, >= 1
  std::uint64_t seed = 1;  // the same seed always gives the same draws
  bool per_pose = true;    // a fresh set of draws each time an outer axis advances
  double min = -1e300;     // truncation, unit of the axis
  double max = 1e300;
  // IsValid() also needs AcceptedFraction() >= kMinAcceptedFraction: a window that keeps fewer
  // draws than that (sd 1e308, or a window 1e-7 wide) would make the draws redraw for ever.
  static constexpr double kMinAcceptedFraction = 0.01;
  bool IsValid(std::string* why) const;
  // The fraction of N(mean, sd) inside [min, max]: the chance that a draw is kept (1 for sd 0).
  double AcceptedFraction() const;
  // The largest sd whose AcceptedFraction() is still kMinAcceptedFraction (the fix to suggest).
  double LargestUsableSd() const;
};

// One axis: an explicit list of values (lists and ranges end up here), or random draws.
struct AxisValues {
  std::vector<double> values;         // in sweep order; used when `random` is empty
  std::optional<RandomDraws> random;  // when set, replaces `values`
  int Count() const;                  // values per set
};

// The frames taken at every pose.
struct BracketSpec {
  double t_ref_ms = 8.0;                                     // reference exposure t_r, ms
  std::vector<double> t_meas_ms = {30.0, 32.0, 34.0, 36.0};  // measurement exposures t_n, ms
  int repeats = 1;                // brackets per pose (the station does not move between them)
  bool retake_reference = false;  // true: t_r is retaken right before each t_n
  bool IsValid(std::string* why) const;  // exposures in (0, kMaxExposureMs]
};

// Bounds that keep every count and duration of a plan far from overflow.
constexpr double kMaxExposureMs = 100000.0;  // one exposure, ms (100 s)
constexpr double kMaxSettleMs = 3600000.0;   // one settle wait, ms (1 h)
constexpr double kMaxPlanFrames = 1e7;       // frames of one plan (int counts; ~10 TB of PNGs)

// Waits the sweep adds on top of the station's own settle (which is in MotionModel).
struct SettleSpec {
  // After the station reports settled (it does so only after its own settle time, and the client
  // waits for consecutive settled polls), before the first frame: raise it on a rig whose
  // platform still rings once its encoders are settled.
  double after_move_ms = 0.0;
  // After the IRED current changes: the current source's electrical settling. The I0-free method
  // tolerates the IRED's slow thermal drift by design (that is the paper's point; the thermal time
  // constant is 60 s on the virtual rig, minutes on a real IRED), so nothing waits for thermal
  // equilibrium. The wait overlaps the move that follows the change (plan and sweep set the
  // current first).
  double after_current_ms = 20.0;
  bool IsValid(std::string* why) const;  // each in [0, kMaxSettleMs]
};

// Everything a sweep plan is made of.
struct SweepSpec {
  AxisValues slide_mm{{2000.0}, {}};
  AxisValues angle_deg{{0.0}, {}};  // theta or pan, see angle_mode
  AxisValues tilt_deg{{0.0}, {}};
  AxisValues bias_ma{{500.0}, {}};
  AngleMode angle_mode = AngleMode::kTheta;
  // Slowest (outermost) axis first; must name each axis once. Empty: chosen by step cost
  // (ChooseAxisOrder), with per-pose random axes innermost.
  std::vector<SweepAxis> order;
  // Axes that reverse direction each time an outer axis advances (boustrophedon), so consecutive
  // poses stay close. No effect on the outermost axis.
  std::vector<SweepAxis> serpentine = {SweepAxis::kSlide, SweepAxis::kAngle, SweepAxis::kTilt};
  BracketSpec bracket;
  SettleSpec settle;
  bool IsValid(std::string* why) const;
};

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

// A station pose of the plan: Pose, station/pose.h.

// One frame of the bracket taken at each pose, in trigger order.
struct PlannedExposure {
  int index = 0;  // position in the bracket, 0-based
  double exposure_ms = 0.0;
  bool is_reference = false;
  int reference_index = -1;  // measurement frame: index of the reference it is differenced with
};

// The bracket's frames, in trigger order: t_r, t_n1, t_n2, ... or, with retake_reference,
// t_r, t_n1, t_r, t_n2, ...
std::vector<PlannedExposure> PlannedExposures(const BracketSpec& bracket);

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
