#pragma once
// A sweep's spec: the four swept axes (values or random draws), the bracket of frames taken at
// each pose and the waits the sweep adds, with their checks. What a recipe says, before it is
// expanded into a plan (station/plan.h MakePlan).
//
// Plain data only: no Asio, no yaml-cpp. app/inputs/recipe.h fills a SweepSpec from a recipe file.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

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

// The values of one axis of the spec.
const AxisValues& AxisOf(const SweepSpec& spec, SweepAxis axis);

}  // namespace irdist
