#include "estimator/track_filter.h"

#include <cmath>

#include <boost/math/distributions/chi_squared.hpp>

#include "base/check.h"

namespace irdist {

bool TrackFilterOptions::IsValid(const char** why) const {
  const char* bad = nullptr;
  if (!(accel_psd_mm2_per_s3 >= 0.0 && std::isfinite(accel_psd_mm2_per_s3))) {
    bad = "the process noise (accel_psd_mm2_per_s3) must be finite and >= 0";
  } else if (!(gate_tail_probability > 0.0 && gate_tail_probability < 0.5)) {
    bad = "the gate's tail probability must lie in (0, 0.5)";
  } else if (reset_after < 1) {
    bad = "reset_after must be at least 1";
  } else if (!(initial_speed_sd_mm_per_s > 0.0 && std::isfinite(initial_speed_sd_mm_per_s))) {
    bad = "the initial speed's sd must be finite and > 0";
  }
  if (why != nullptr) *why = bad;
  return bad == nullptr;
}

TrackFilter::TrackFilter(int axes, const TrackFilterOptions& options)
    : options_(options), axes_(static_cast<size_t>(axes > 0 ? axes : 0)) {
  const char* why = nullptr;
  IRDIST_CHECK(axes >= 1 && axes <= 3, "a track has 1 to 3 axes, not ", axes);
  IRDIST_CHECK(options.IsValid(&why), why);
  const boost::math::chi_squared chi2(static_cast<double>(axes));
  gate_chi2_ = boost::math::quantile(boost::math::complement(chi2, options.gate_tail_probability));
}

void TrackFilter::Start(double time_s, const std::vector<double>& z,
                        const std::vector<double>& sd) {
  const double speed_var = options_.initial_speed_sd_mm_per_s * options_.initial_speed_sd_mm_per_s;
  for (size_t i = 0; i < axes_.size(); ++i) axes_[i] = {z[i], 0.0, sd[i] * sd[i], 0.0, speed_var};
  started_ = true;
  last_time_s_ = time_s;
  frames_ = 1;
  rejected_in_row_ = 0;
}

void TrackFilter::Predict(double dt_s) {
  const double q = options_.accel_psd_mm2_per_s3;
  for (Axis& a : axes_) {
    a.p += a.v * dt_s;
    // F P F^T + Q with F = [[1, dt], [0, 1]].
    a.ppp += dt_s * (2.0 * a.ppv + dt_s * a.pvv) + q * dt_s * dt_s * dt_s / 3.0;
    a.ppv += dt_s * a.pvv + q * dt_s * dt_s / 2.0;
    a.pvv += q * dt_s;
  }
}

TrackState TrackFilter::State(double time_s) const {
  TrackState s;
  s.time_s = time_s;
  s.frames = frames_;
  for (const Axis& a : axes_) {
    s.position_mm.push_back(a.p);
    s.position_sd_mm.push_back(std::sqrt(a.ppp));
    s.velocity_mm_per_s.push_back(a.v);
    s.velocity_sd_mm_per_s.push_back(std::sqrt(a.pvv));
  }
  return s;
}

TrackState TrackFilter::Gated(double time_s, const std::vector<double>& position_mm,
                              const std::vector<double>& sd_mm, double chi2) {
  // Frames that agree with the previous gated one count towards a restart.
  double apart = 0.0;
  for (size_t i = 0; rejected_in_row_ > 0 && i < axes_.size(); ++i) {
    const double d = position_mm[i] - last_rejected_[i];
    apart += d * d / (sd_mm[i] * sd_mm[i] + last_rejected_sd_[i] * last_rejected_sd_[i]);
  }
  rejected_in_row_ = apart > gate_chi2_ ? 1 : rejected_in_row_ + 1;
  last_rejected_ = position_mm;
  last_rejected_sd_ = sd_mm;
  const bool restart = rejected_in_row_ >= options_.reset_after;
  if (restart) Start(time_s, position_mm, sd_mm);
  TrackState s = State(time_s);
  s.chi2 = chi2;
  s.used = s.started = restart;
  return s;
}

void TrackFilter::Update(const std::vector<double>& position_mm,
                         const std::vector<double>& sd_mm) {
  for (size_t i = 0; i < axes_.size(); ++i) {
    Axis& a = axes_[i];
    const double r = sd_mm[i] * sd_mm[i];
    const double s = a.ppp + r;
    const double kp = a.ppp / s, kv = a.ppv / s;  // the gain K = P H^T / S
    const double y = position_mm[i] - a.p;
    a.p += kp * y;
    a.v += kv * y;
    // Joseph form (I - K H) P (I - K H)^T + K R K^T: symmetric and positive whatever the rounding.
    const double pp = (1 - kp) * (1 - kp) * a.ppp + kp * kp * r;
    const double pv = (1 - kp) * (a.ppv - kv * a.ppp) + kp * kv * r;
    const double vv = a.pvv - 2.0 * kv * a.ppv + kv * kv * a.ppp + kv * kv * r;
    a.ppp = pp, a.ppv = pv, a.pvv = vv;
  }
}

TrackState TrackFilter::Add(double time_s, const std::vector<double>& position_mm,
                            const std::vector<double>& sd_mm) {
  IRDIST_CHECK(position_mm.size() == axes_.size() && sd_mm.size() == axes_.size(),
               "a frame of the track needs ", axes_.size(), " values and standard errors");
  IRDIST_CHECK(std::isfinite(time_s), "a frame's time must be finite");
  IRDIST_CHECK(!started_ || time_s > last_time_s_, "frame time ", time_s,
               " s is not after the last frame's ", last_time_s_, " s");
  bool finite = true;
  for (size_t i = 0; i < axes_.size(); ++i) {
    finite = finite && std::isfinite(position_mm[i]) && std::isfinite(sd_mm[i]) && sd_mm[i] > 0.0;
  }
  if (!finite) {  // no measurement: the prediction, if there is a track
    if (started_) {
      Predict(time_s - last_time_s_);
      last_time_s_ = time_s;
    }
    return State(time_s);
  }
  if (!started_) {
    Start(time_s, position_mm, sd_mm);
    TrackState s = State(time_s);
    s.used = s.started = true;
    return s;
  }
  Predict(time_s - last_time_s_);
  last_time_s_ = time_s;
  double chi2 = 0.0;
  for (size_t i = 0; i < axes_.size(); ++i) {
    const double y = position_mm[i] - axes_[i].p;
    chi2 += y * y / (axes_[i].ppp + sd_mm[i] * sd_mm[i]);
  }
  if (chi2 > gate_chi2_) return Gated(time_s, position_mm, sd_mm, chi2);
  Update(position_mm, sd_mm);
  rejected_in_row_ = 0;
  ++frames_;
  TrackState s = State(time_s);
  s.chi2 = chi2;
  s.used = true;
  return s;
}

}  // namespace irdist
