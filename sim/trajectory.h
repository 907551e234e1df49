#pragma once
// The station's trajectory as a function of simulated time: for each axis (slide in mm, pan and
// tilt in deg) the motion profiles it followed (sim/motion_profile.h), each in force from its
// start until the next one's. The pose at any instant is computed from the profiles, exactly (no
// sampling): the truth of a frame is the pose at the middle of its exposure (docs/virtual-rig.md,
// "Truth of a moving target"). Kept by the World (sim/world.h), written to a CSV file by
// sim/trajectory_file.h and read back from it for tests and the validation.

#include <array>
#include <cstdint>
#include <deque>
#include <string>

#include "sim/motion_profile.h"

namespace irdist::sim {

// The rig's axes, in the order of the station protocol's MOVE.
enum class RigAxis : int { kSlide = 0, kPan = 1, kTilt = 2 };
constexpr int kRigAxes = 3;
// "slide", "pan", "tilt"; and the unit of the axis's positions ("mm", "deg").
const char* RigAxisName(RigAxis axis);
const char* RigAxisUnit(RigAxis axis);

// The IRED's pose at one instant, with its velocity.
struct TrajectoryPoint {
  double time_s = 0.0;        // simulated time
  double slide_mm = 0.0;
  double pan_deg = 0.0;
  double tilt_deg = 0.0;
  double theta_deg = 0.0;     // cos(theta) = cos(pan) cos(tilt) (sim/world.h)
  double slide_mm_s = 0.0;    // signed velocities
  double pan_deg_s = 0.0;
  double tilt_deg_s = 0.0;
  bool known = false;         // every axis had a profile at time_s (else the values are 0)
};

class Trajectory {
 public:
  // Profiles kept per axis (the oldest are forgotten: a frame's truth is asked for at once).
  static constexpr std::size_t kKeptPerAxis = 100000;

  // `profile` is in force from profile.start_s on; a later profile of the same axis that started
  // earlier is dropped (the axis's history is rewritten from that instant).
  void Add(RigAxis axis, const MotionProfile& profile);
  // The pose at simulated time t_s: each axis's position from its last profile started at or
  // before t_s (before the first one: the first one's start position, at rest).
  TrajectoryPoint At(double t_s) const;
  bool Has(RigAxis axis) const { return !axes_[static_cast<int>(axis)].empty(); }
  const std::deque<MotionProfile>& Profiles(RigAxis axis) const {
    return axes_[static_cast<int>(axis)];
  }

 private:
  std::array<std::deque<MotionProfile>, kRigAxes> axes_;
};

// The truth of one frame from its camera timestamp (the exposure's start, sim ns) and exposure:
// the pose and velocities at the middle of its exposure.
TrajectoryPoint MidExposure(const Trajectory& trajectory, std::uint64_t timestamp_ns,
                            double exposure_us);

// theta from pan and tilt (deg), as PoseState::ThetaDeg.
double ThetaDegOf(double pan_deg, double tilt_deg);

// Simulated seconds <-> the camera's timestamp in ns (the world's clock mapped to ns).
std::uint64_t SimTimeToNs(double sim_s);
double NsToSimTime(std::uint64_t ns);

}  // namespace irdist::sim
