#include "sim/trajectory.h"

#include <algorithm>
#include <cmath>

#include "base/pi.h"

namespace irdist::sim {

const char* RigAxisName(RigAxis axis) {
  switch (axis) {
    case RigAxis::kSlide: return "slide";
    case RigAxis::kPan: return "pan";
    case RigAxis::kTilt: return "tilt";
  }
  return "?";
}

const char* RigAxisUnit(RigAxis axis) { return axis == RigAxis::kSlide ? "mm" : "deg"; }

double ThetaDegOf(double pan_deg, double tilt_deg) {
  constexpr double kDeg = kPi / 180.0;
  const double c = std::cos(pan_deg * kDeg) * std::cos(tilt_deg * kDeg);
  return std::acos(std::fmin(1.0, std::fmax(-1.0, c))) / kDeg;
}

std::uint64_t SimTimeToNs(double sim_s) {
  return sim_s <= 0.0 ? 0 : static_cast<std::uint64_t>(std::llround(sim_s * 1e9));
}

double NsToSimTime(std::uint64_t ns) { return static_cast<double>(ns) * 1e-9; }

void Trajectory::Add(RigAxis axis, const MotionProfile& profile) {
  std::deque<MotionProfile>& list = axes_[static_cast<int>(axis)];
  while (!list.empty() && list.back().start_s > profile.start_s) list.pop_back();
  list.push_back(profile);
  while (list.size() > kKeptPerAxis) list.pop_front();
}

TrajectoryPoint Trajectory::At(double t_s) const {
  TrajectoryPoint point;
  point.time_s = t_s;
  point.known = true;
  std::array<double, kRigAxes> pos{}, vel{};
  for (int i = 0; i < kRigAxes; ++i) {
    const std::deque<MotionProfile>& list = axes_[i];
    if (list.empty()) {
      point.known = false;
      continue;
    }
    // The last profile started at or before t_s.
    auto after = std::upper_bound(
        list.begin(), list.end(), t_s,
        [](double t, const MotionProfile& p) { return t < p.start_s; });
    const MotionProfile& p = after == list.begin() ? list.front() : *(after - 1);
    pos[i] = p.PositionAt(t_s);
    vel[i] = p.VelocityAt(t_s);
  }
  point.slide_mm = pos[0];
  point.pan_deg = pos[1];
  point.tilt_deg = pos[2];
  point.slide_mm_s = vel[0];
  point.pan_deg_s = vel[1];
  point.tilt_deg_s = vel[2];
  point.theta_deg = ThetaDegOf(point.pan_deg, point.tilt_deg);
  return point;
}

TrajectoryPoint MidExposure(const Trajectory& trajectory, std::uint64_t timestamp_ns,
                            double exposure_us) {
  return trajectory.At(NsToSimTime(timestamp_ns) + 0.5 * exposure_us * 1e-6);
}

}  // namespace irdist::sim
