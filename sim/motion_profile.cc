#include "sim/motion_profile.h"

#include <algorithm>
#include <cmath>

namespace irdist::sim {

MotionProfile MotionProfile::Make(double from, double to, double start_s, double v0, double vmax,
                                  double a) {
  MotionProfile p;
  p.from = from;
  p.to = to;
  p.start_s = start_s;
  p.accel = a;
  const double d = std::fabs(to - from);
  v0 = std::min(v0, std::sqrt(2.0 * a * d));  // cannot overshoot
  p.v0 = v0;
  if (d <= 0.0) return p;
  if (d >= (2.0 * vmax * vmax - v0 * v0) / (2.0 * a)) {
    p.vp = std::max(vmax, v0);
    const double d_acc = (p.vp * p.vp - v0 * v0) / (2.0 * a);
    const double d_dec = p.vp * p.vp / (2.0 * a);
    p.t_acc = (p.vp - v0) / a;
    p.t_dec = p.vp / a;
    p.t_cruise = std::max(0.0, (d - d_acc - d_dec) / p.vp);
  } else {
    p.vp = std::sqrt((2.0 * a * d + v0 * v0) / 2.0);
    p.t_acc = (p.vp - v0) / a;
    p.t_dec = p.vp / a;
  }
  return p;
}

MotionProfile MotionProfile::Rest(double position, double start_s) {
  MotionProfile p;
  p.from = position;
  p.to = position;
  p.start_s = start_s;
  return p;
}

void MotionProfile::At(double tau, double* pos, double* speed) const {
  const double dir = to >= from ? 1.0 : -1.0;
  const double s_acc = v0 * t_acc + 0.5 * accel * t_acc * t_acc;
  double s = 0.0, v = 0.0;
  if (tau <= 0.0) {
    v = v0;
  } else if (tau < t_acc) {
    s = v0 * tau + 0.5 * accel * tau * tau;
    v = v0 + accel * tau;
  } else if (tau < t_acc + t_cruise) {
    s = s_acc + vp * (tau - t_acc);
    v = vp;
  } else if (tau < Duration()) {
    const double u = tau - t_acc - t_cruise;
    s = s_acc + vp * t_cruise + vp * u - 0.5 * accel * u * u;
    v = vp - accel * u;
  } else {
    *pos = to;
    *speed = 0.0;
    return;
  }
  *pos = from + dir * std::min(s, std::fabs(to - from));
  *speed = v;
}

double MotionProfile::PositionAt(double t_s) const {
  double pos = 0.0, speed = 0.0;
  At(t_s - start_s, &pos, &speed);
  return pos;
}

double MotionProfile::VelocityAt(double t_s) const {
  if (t_s < start_s || to == from) return 0.0;
  double pos = 0.0, speed = 0.0;
  At(t_s - start_s, &pos, &speed);
  return to >= from ? speed : -speed;
}

}  // namespace irdist::sim
