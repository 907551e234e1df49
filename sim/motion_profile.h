#pragma once
// One axis's motion in simulated time: a trapezoidal (or triangular) speed profile from rest, or
// from an initial speed v0 in the direction of travel, ending at rest at `to`. The station model
// (sim/station_model.cc) moves its axes along these, and the World keeps them as the exact
// trajectory (sim/trajectory.h): the position at any instant follows from the profile, not from
// samples. Units are the axis's own (mm for the slide, deg for pan and tilt).

namespace irdist::sim {

struct MotionProfile {
  double from = 0.0;        // position at start_s
  double to = 0.0;          // position at rest at the end
  double start_s = 0.0;     // simulated time the profile starts
  double v0 = 0.0;          // speed at start_s, towards `to` (>= 0)
  double vp = 0.0;          // peak (cruise) speed
  double accel = 1.0;       // acceleration and deceleration (> 0)
  double t_acc = 0.0;       // seconds accelerating from v0 to vp
  double t_cruise = 0.0;    // seconds at vp
  double t_dec = 0.0;       // seconds decelerating from vp to rest

  // The profile from `from` to `to` starting at `start_s` with speed `v0`, cruise speed at most
  // `vmax` (at least v0) and acceleration `a`. from == to: at rest.
  static MotionProfile Make(double from, double to, double start_s, double v0, double vmax,
                            double a);
  // At rest at `position` from `start_s` on.
  static MotionProfile Rest(double position, double start_s);

  double Duration() const { return t_acc + t_cruise + t_dec; }
  double EndS() const { return start_s + Duration(); }
  // Position and speed (unsigned, along the direction of travel) `tau` seconds after start_s.
  void At(double tau, double* pos, double* speed) const;
  // Position and signed velocity (unit/s) at simulated time t_s (before start_s: `from`).
  double PositionAt(double t_s) const;
  double VelocityAt(double t_s) const;
};

}  // namespace irdist::sim
