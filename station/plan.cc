#include "station/plan.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <limits>
#include <random>
#include <sstream>

#include "base/check.h"
#include "base/pi.h"

namespace irdist {
namespace {

constexpr double kSameValue = 1e-9;  // two axis values closer than this are the same position

double DegToRad(double deg) { return deg * kPi / 180.0; }
double RadToDeg(double rad) { return rad * 180.0 / kPi; }

bool Fail(std::string* why, const std::string& message) {
  if (why != nullptr) *why = message;
  return false;
}

// Deterministic normal draws: mt19937_64 (specified bit for bit by the standard) and Box-Muller
// written here, since std::normal_distribution differs between standard libraries.
class NormalSource {
 public:
  explicit NormalSource(std::uint64_t seed) : engine_(seed) {}
  double Next() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    constexpr double kScale = 1.0 / 9007199254740992.0;  // 2^-53
    double u1 = 0.0;
    while (u1 <= 0.0) u1 = static_cast<double>(engine_() >> 11) * kScale;
    const double u2 = static_cast<double>(engine_() >> 11) * kScale;
    const double r = std::sqrt(-2.0 * std::log(u1));
    spare_ = r * std::sin(2.0 * kPi * u2);
    has_spare_ = true;
    return r * std::cos(2.0 * kPi * u2);
  }

 private:
  std::mt19937_64 engine_;
  bool has_spare_ = false;
  double spare_ = 0.0;
};

// Rejection sampling of the truncated normal. IsValid() keeps at least 1% of the draws, so the
// bound on attempts (the expected count times a thousand, and more) is never reached by a valid
// spec: it only turns a spec that skipped IsValid() into an error instead of a spin.
std::vector<double> DrawSet(const RandomDraws& draws, NormalSource* source) {
  std::vector<double> values;
  values.reserve(static_cast<size_t>(draws.count));
  const long max_attempts = 100000L + 100000L * draws.count;
  for (long attempt = 0; static_cast<int>(values.size()) < draws.count; ++attempt) {
    IRDIST_CHECK(attempt < max_attempts, "random draws N(", draws.mean, ", ", draws.sd,
                 ") kept ", values.size(), " of ", attempt, " inside [", draws.min, ", ",
                 draws.max, "]; RandomDraws::IsValid() refuses such a window");
    const double v = draws.mean + draws.sd * source->Next();
    if (v >= draws.min && v <= draws.max) values.push_back(v);
  }
  return values;
}

double MedianStep(const AxisValues& axis) {
  if (axis.random.has_value()) return axis.random->sd;
  std::vector<double> sorted = axis.values;
  std::sort(sorted.begin(), sorted.end());
  std::vector<double> steps;
  for (size_t i = 1; i < sorted.size(); ++i) {
    if (sorted[i] - sorted[i - 1] > kSameValue) steps.push_back(sorted[i] - sorted[i - 1]);
  }
  if (steps.empty()) return 0.0;
  const auto middle = steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2);
  std::nth_element(steps.begin(), middle, steps.end());
  return steps[steps.size() / 2];
}

std::string Seconds(double s) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.1f s", s);
  return buffer;
}

}  // namespace

bool MotionModel::IsValid(std::string* why) const {
  const std::array<std::pair<const char*, const AxisMotion*>, 3> axes = {
      {{"slide", &slide}, {"pan", &pan}, {"tilt", &tilt}}};
  for (const auto& [name, axis] : axes) {
    if (!(axis->speed > 0.0) || !std::isfinite(axis->speed)) {
      return Fail(why, std::string(name) + ".speed must be > 0");
    }
    if (!(axis->acceleration > 0.0) || !std::isfinite(axis->acceleration)) {
      return Fail(why, std::string(name) + ".acceleration must be > 0");
    }
    if (!(axis->settle_ms >= 0.0)) return Fail(why, std::string(name) + ".settle_ms must be >= 0");
  }
  if (!(readout_ms >= 0.0)) return Fail(why, "readout_ms must be >= 0");
  if (!(frame_overhead_ms >= 0.0)) return Fail(why, "frame_overhead_ms must be >= 0");
  if (!(pose_overhead_ms >= 0.0)) return Fail(why, "pose_overhead_ms must be >= 0");
  return true;
}

double TrapezoidMoveS(double distance, const AxisMotion& motion) {
  IRDIST_CHECK(motion.speed > 0.0 && motion.acceleration > 0.0, "bad AxisMotion");
  const double d = std::abs(distance);
  if (d <= 0.0) return 0.0;
  const double v = motion.speed;
  const double a = motion.acceleration;
  // Accelerating to v and back down covers v^2/a; shorter moves never reach cruise speed.
  if (d >= v * v / a) return d / v + v / a;
  return 2.0 * std::sqrt(d / a);
}

std::vector<SweepAxis> ChooseAxisOrder(const SweepSpec& spec, const MotionModel& motion) {
  const std::array<SweepAxis, 4> canonical = {SweepAxis::kSlide, SweepAxis::kAngle,
                                              SweepAxis::kTilt, SweepAxis::kBias};
  constexpr double kInf = std::numeric_limits<double>::infinity();
  auto cost = [&](SweepAxis axis) {
    const AxisValues& values = AxisOf(spec, axis);
    if (values.random.has_value() && values.random->per_pose) return -kInf;
    if (values.Count() <= 1) return -1.0;  // never changes: innermost, before per-pose draws
    const double step = MedianStep(values);
    const double move_settle_s = spec.settle.after_move_ms / 1000.0;
    switch (axis) {
      case SweepAxis::kSlide:
        return TrapezoidMoveS(step, motion.slide) + motion.slide.settle_ms / 1000.0 + move_settle_s;
      case SweepAxis::kAngle:
        return TrapezoidMoveS(step, motion.pan) + motion.pan.settle_ms / 1000.0 + move_settle_s;
      case SweepAxis::kTilt:
        return TrapezoidMoveS(step, motion.tilt) + motion.tilt.settle_ms / 1000.0 + move_settle_s;
      case SweepAxis::kBias:
        return spec.settle.after_current_ms / 1000.0;
    }
    return 0.0;
  };
  std::vector<std::pair<double, SweepAxis>> ranked;
  ranked.reserve(canonical.size());
  for (SweepAxis axis : canonical) ranked.emplace_back(cost(axis), axis);
  std::stable_sort(ranked.begin(), ranked.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  std::vector<SweepAxis> order;
  order.reserve(ranked.size());
  for (const auto& entry : ranked) order.push_back(entry.second);
  return order;
}

namespace {

// A pose from the swept values (indexed by SweepAxis): pan and theta from the angle and the tilt.
Pose PoseFromValues(const SweepSpec& spec, const std::array<double, 4>& value) {
  Pose pose;
  pose.slide_mm = value[static_cast<size_t>(SweepAxis::kSlide)];
  pose.tilt_deg = value[static_cast<size_t>(SweepAxis::kTilt)];
  pose.bias_ma = value[static_cast<size_t>(SweepAxis::kBias)];
  const double angle = value[static_cast<size_t>(SweepAxis::kAngle)];
  const double cos_tilt = std::cos(DegToRad(pose.tilt_deg));
  if (spec.angle_mode == AngleMode::kTheta) {
    const double c = std::cos(DegToRad(angle)) / cos_tilt;
    IRDIST_CHECK(c <= 1.0 + 1e-12, "theta ", angle, " deg cannot be reached with tilt ",
                 pose.tilt_deg, " deg: |theta| must be >= |tilt|");
    const double pan = RadToDeg(std::acos(std::min(1.0, c)));
    pose.theta_deg = angle;
    // At tilt 0 the pan is theta itself, exactly (acos(cos x) is off by an ulp or two).
    pose.pan_deg = pose.tilt_deg == 0.0 ? angle : (angle < 0.0 ? -pan : pan);
  } else {
    pose.pan_deg = angle;
    pose.theta_deg = RadToDeg(std::acos(std::min(1.0, std::cos(DegToRad(angle)) * cos_tilt)));
  }
  return pose;
}

// The axes' values in sweep order: a mixed-radix counter over the axes (outermost first), with
// serpentine axes reversed on odd outer passes and random axes drawn per outer combination.
class AxisOdometer {
 public:
  AxisOdometer(const SweepSpec& spec, const std::vector<SweepAxis>& order)
      : spec_(spec), order_(order), counts_(order.size()), digit_(order.size(), 0) {
    for (size_t k = 0; k < order.size(); ++k) {
      const AxisValues& values = AxisOf(spec, order[k]);
      counts_[k] = values.Count();
      combinations_ *= counts_[k];
      if (values.random.has_value()) {
        sources_[k].emplace(values.random->seed);
      } else {
        current_set_[k] = values.values;
      }
    }
  }
  long combinations() const { return combinations_; }
  // The values (indexed by SweepAxis) of combination `flat`, visited in increasing order.
  std::array<double, 4> Values(long flat) {
    long rest = flat;
    for (size_t k = order_.size(); k-- > 0;) {
      digit_[k] = static_cast<int>(rest % counts_[k]);
      rest /= counts_[k];
    }
    std::array<double, 4> value{};
    long outer = 0;  // flattened index over the axes outside k
    for (size_t k = 0; k < order_.size(); ++k) {
      const AxisValues& values = AxisOf(spec_, order_[k]);
      if (values.random.has_value()) {
        const long wanted = values.random->per_pose ? outer : 0;
        if (set_outer_[k] != wanted) {
          current_set_[k] = DrawSet(*values.random, &*sources_[k]);
          set_outer_[k] = wanted;
        }
      }
      const bool snake = k > 0 && outer % 2 == 1 &&
                         std::find(spec_.serpentine.begin(), spec_.serpentine.end(),
                                   order_[k]) != spec_.serpentine.end();
      const int i = snake ? counts_[k] - 1 - digit_[k] : digit_[k];
      value[static_cast<size_t>(order_[k])] = current_set_[k][static_cast<size_t>(i)];
      outer = outer * counts_[k] + digit_[k];
    }
    return value;
  }

 private:
  const SweepSpec& spec_;
  const std::vector<SweepAxis>& order_;
  std::vector<int> counts_;
  std::vector<int> digit_;
  long combinations_ = 1;
  std::array<std::optional<NormalSource>, 4> sources_;
  std::array<std::vector<double>, 4> current_set_;  // each axis's values for this outer pass
  std::array<long, 4> set_outer_ = {-1, -1, -1, -1};
};

// The move from `previous` (nullptr: from where homing left the station) to `pose`: profile time
// and the moved axes' settle, s. Returns whether any axis moves.
bool MoveCost(const Pose* previous, const Pose& pose, const MotionModel& motion, double* move_s,
              double* settle_s) {
  const std::array<std::pair<double, const AxisMotion*>, 3> deltas = {
      {{pose.slide_mm - (previous ? previous->slide_mm : motion.slide.home), &motion.slide},
       {pose.pan_deg - (previous ? previous->pan_deg : motion.pan.home), &motion.pan},
       {pose.tilt_deg - (previous ? previous->tilt_deg : motion.tilt.home), &motion.tilt}}};
  bool moved = false;
  *move_s = 0.0;
  *settle_s = 0.0;
  for (const auto& [delta, axis] : deltas) {
    if (std::abs(delta) <= kSameValue) continue;
    moved = true;
    const double t = TrapezoidMoveS(delta, *axis);
    if (motion.axes_move_together) {
      *move_s = std::max(*move_s, t);
      *settle_s = std::max(*settle_s, axis->settle_ms / 1000.0);
    } else {
      *move_s += t;
      *settle_s += axis->settle_ms / 1000.0;
    }
  }
  return moved;
}

// The counts, in 64 bits first: a plan of more than kMaxPlanFrames frames is refused before its
// int counts could overflow.
void CountFrames(Plan* plan) {
  PlanSummary& summary = plan->summary;
  const std::int64_t poses = static_cast<std::int64_t>(plan->poses.size());
  const std::int64_t frames_per_pose = static_cast<std::int64_t>(plan->bracket.size());
  const std::int64_t frames = poses * frames_per_pose;
  IRDIST_CHECK(static_cast<double>(frames) <= kMaxPlanFrames, "the plan has ", poses, " poses x ",
               frames_per_pose, " frames = ", frames, " frames; at most ", kMaxPlanFrames);
  summary.pose_count = static_cast<int>(poses);
  summary.frames_per_pose = static_cast<int>(frames_per_pose);
  summary.frame_count = static_cast<int>(frames);
  const std::int64_t differences_per_pose =
      std::count_if(plan->bracket.begin(), plan->bracket.end(),
                    [](const PlannedExposure& f) { return !f.is_reference; });
  summary.difference_count = static_cast<int>(poses * differences_per_pose);
}

// The duration estimate and the physical bound, pose by pose.
void EstimateDuration(const SweepSpec& spec, const MotionModel& motion, Plan* plan) {
  PlanSummary& summary = plan->summary;
  CountFrames(plan);
  double bracket_exposure_s = 0.0;
  for (const PlannedExposure& f : plan->bracket) bracket_exposure_s += f.exposure_ms / 1000.0;
  const double frames_per_pose = static_cast<double>(plan->bracket.size());
  const Pose* previous = nullptr;
  for (const Pose& pose : plan->poses) {
    double move_s = 0.0, settle_s = 0.0;
    const bool moved = MoveCost(previous, pose, motion, &move_s, &settle_s);
    summary.motion_s += move_s;
    summary.station_settle_s += settle_s;
    double travel_s = move_s + settle_s;  // move, station settle and the recipe's wait after it
    if (moved) {
      ++summary.moves;
      summary.move_settle_s += spec.settle.after_move_ms / 1000.0;
      travel_s += spec.settle.after_move_ms / 1000.0;
    }
    if (previous == nullptr || std::abs(pose.bias_ma - previous->bias_ma) > kSameValue) {
      // The current is set before the move, so its settle runs while the axes travel: only what
      // is left of it afterwards costs time.
      ++summary.current_changes;
      summary.current_settle_s +=
          std::max(0.0, spec.settle.after_current_ms / 1000.0 - travel_s);
    }
    summary.exposure_s += bracket_exposure_s;
    summary.readout_s += frames_per_pose * motion.readout_ms / 1000.0;
    summary.overhead_s +=
        (frames_per_pose * motion.frame_overhead_ms + motion.pose_overhead_ms) / 1000.0;
    previous = &pose;
  }
  summary.total_s = summary.motion_s + summary.station_settle_s + summary.move_settle_s +
                    summary.current_settle_s + summary.exposure_s + summary.readout_s +
                    summary.overhead_s;
  summary.physical_bound_s =
      summary.motion_s + summary.station_settle_s + summary.exposure_s + summary.readout_s;
}

}  // namespace

MotionModel WithDeviceSpeeds(MotionModel model, const std::map<Axis, AxisSpeed>& speeds) {
  const std::pair<Axis, AxisMotion*> axes[] = {
      {Axis::kSlide, &model.slide}, {Axis::kPan, &model.pan}, {Axis::kTilt, &model.tilt}};
  for (const auto& [axis, motion] : axes) {
    const auto found = speeds.find(axis);
    if (found == speeds.end()) continue;
    const AxisSpeed& device = found->second;
    if (device.speed > 0.0 && device.acceleration > 0.0) {
      *motion = {device.speed, device.acceleration, device.settle_ms, device.home};
    }
  }
  return model;
}

Plan MakePlan(const SweepSpec& spec, const MotionModel& motion) {
  std::string why;
  IRDIST_CHECK(spec.IsValid(&why), why);
  IRDIST_CHECK(motion.IsValid(&why), why);
  const std::vector<SweepAxis> order =
      spec.order.empty() ? ChooseAxisOrder(spec, motion) : spec.order;
  const int repeats = spec.bracket.repeats;

  Plan plan;
  plan.bracket = PlannedExposures(spec.bracket);
  for (SweepAxis axis : order) {
    plan.summary.order.push_back(SweepAxisName(axis, spec.angle_mode));
    plan.summary.axis_counts.push_back(AxisOf(spec, axis).Count());
  }
  plan.summary.repeats = repeats;

  AxisOdometer odometer(spec, order);
  plan.poses.reserve(static_cast<size_t>(odometer.combinations() * repeats));
  for (long flat = 0; flat < odometer.combinations(); ++flat) {
    Pose pose = PoseFromValues(spec, odometer.Values(flat));
    for (int r = 0; r < repeats; ++r) {
      pose.repeat = r;
      pose.index = static_cast<std::int64_t>(plan.poses.size());
      plan.poses.push_back(pose);
    }
  }
  EstimateDuration(spec, motion, &plan);
  return plan;
}

std::string FormatDuration(double seconds) {
  char buffer[64];
  if (!(seconds <= 1e9)) return "over 1e9 s";  // also infinite and NaN: never lround() them
  if (seconds < 60.0) {
    std::snprintf(buffer, sizeof(buffer), "%.1f s", seconds);
  } else if (seconds < 3600.0) {
    const int minutes = static_cast<int>(seconds / 60.0);
    std::snprintf(buffer, sizeof(buffer), "%dm %04.1fs", minutes, seconds - 60.0 * minutes);
  } else {
    const long total = std::lround(seconds);
    std::snprintf(buffer, sizeof(buffer), "%ldh %02ldm %02lds", total / 3600, (total / 60) % 60,
                  total % 60);
  }
  return buffer;
}

std::string PlanSummary::BriefReport() const {
  std::ostringstream out;
  out << "Grid: ";
  for (size_t k = 0; k < order.size(); ++k) {
    if (k > 0) out << " x ";
    out << order[k] << " " << axis_counts[k];
  }
  out << " (outermost first) x " << repeats << (repeats == 1 ? " repeat" : " repeats") << " = "
      << pose_count << " poses\n";
  out << "Frames: " << frames_per_pose << " per pose, " << frame_count << " in all; "
      << difference_count << " differences\n";
  out << "Estimated duration: " << FormatDuration(total_s) << "\n";
  out << "  motion            " << Seconds(motion_s) << " (" << moves
      << " moves, trapezoidal profiles; homing not included)\n";
  out << "  station settle    " << Seconds(station_settle_s) << "\n";
  out << "  settle after move " << Seconds(move_settle_s) << "\n";
  out << "  current settle    " << Seconds(current_settle_s) << " (" << current_changes
      << " current changes)\n";
  out << "  exposure          " << Seconds(exposure_s) << "\n";
  out << "  readout           " << Seconds(readout_s) << "\n";
  out << "  overhead          " << Seconds(overhead_s) << " (per frame and per pose)\n";
  out << "Physical bound (moves + exposures + readout): " << FormatDuration(physical_bound_s);
  return out.str();
}

}  // namespace irdist
