#pragma once
// A constant-velocity track of a moving IRED: per-frame estimates (the distance, or the
// 3D position in mm) smoothed by a Kalman filter whose state is each axis's position and velocity,
// driven by white acceleration noise of power spectral density q (mm^2/s^3, one per track: the
// filter's process noise, a rig or command option). Between frames dt apart the state moves as
//   p' = p + v dt,  v' = v,  Q = q [[dt^3/3, dt^2/2], [dt^2/2, dt]]   (per axis, independent),
// and a frame's measurement is the position with its standard error (the estimate's own, e.g.
// d_se_mm). A frame whose innovation lies beyond the gate (the chi-square of the axes'
// innovations over their variances, above the quantile of probability 1 - gate_tail_probability)
// is an outlier: reported, not used. `reset_after` such frames in a row that agree with each other
// (the target jumped, or the track was lost) start the track again from the last of them.
// The velocity's standard error is the filter's own: honest only while the motion is as smooth as q
// says (a sharper manoeuvre than q allows shows as gated frames). docs/measure.md "Tracking".

#include <vector>

namespace irdist {

struct TrackFilterOptions {
  // White-acceleration power spectral density, mm^2/s^3: q = a^2 dt_manoeuvre is the usual sizing
  // (accelerations of a mm/s^2 sustained over dt_manoeuvre s). Default: 1e5 (about 0.3 m/s^2
  // sustained for 1 s, a hand-held probe or a slow robot).
  double accel_psd_mm2_per_s3 = 1e5;
  // The gate's tail probability: a frame with chi-square beyond the quantile of 1 - this, for as
  // many degrees of freedom as axes, is an outlier (1e-6: 24 for one axis, 31 for three).
  double gate_tail_probability = 1e-6;
  int reset_after = 3;
  // The first frame's velocity standard error (mm/s): the prior of a track's start.
  double initial_speed_sd_mm_per_s = 1000.0;
  // Whether the options hold (finite, q >= 0, 0 < tail < 0.5, reset_after >= 1, speed sd > 0);
  // *why names the first that does not.
  bool IsValid(const char** why) const;
};

// One frame's output: the smoothed position and velocity per axis with their standard errors.
struct TrackState {
  double time_s = 0.0;
  std::vector<double> position_mm, position_sd_mm;
  std::vector<double> velocity_mm_per_s, velocity_sd_mm_per_s;
  double chi2 = 0.0;      // the frame's gated statistic (0 for a track's first frame)
  bool used = false;      // the frame updated the track
  bool started = false;   // the frame started (or restarted) the track
  int frames = 0;         // frames used since the track (re)started
};

class TrackFilter {
 public:
  // axes: 1 (the distance) to 3 (the position); throws CheckError on invalid options.
  TrackFilter(int axes, const TrackFilterOptions& options = {});
  // Adds a frame taken at time_s (s, increasing: a frame at or before the last one is refused
  // with CheckError) measuring `position_mm` with standard errors `sd_mm` (> 0, finite; a
  // frame with a non-finite value is not used and not counted as an outlier).
  TrackState Add(double time_s, const std::vector<double>& position_mm,
                 const std::vector<double>& sd_mm);
  bool started() const { return started_; }

 private:
  struct Axis {
    double p = 0.0, v = 0.0;
    double ppp = 0.0, ppv = 0.0, pvv = 0.0;  // the covariance [[pp, pv], [pv, vv]]
  };
  void Start(double time_s, const std::vector<double>& z, const std::vector<double>& sd);
  void Predict(double dt_s);
  // A frame beyond the gate: counted towards a restart (which it may make).
  TrackState Gated(double time_s, const std::vector<double>& position_mm,
                   const std::vector<double>& sd_mm, double chi2);
  // The Kalman update of every axis with one frame (Joseph form).
  void Update(const std::vector<double>& position_mm, const std::vector<double>& sd_mm);
  TrackState State(double time_s) const;

  TrackFilterOptions options_;
  double gate_chi2_ = 0.0;
  std::vector<Axis> axes_;
  bool started_ = false;
  double last_time_s_ = 0.0;
  int frames_ = 0;
  int rejected_in_row_ = 0;
  std::vector<double> last_rejected_;  // the last gated frame's position (for a restart)
  std::vector<double> last_rejected_sd_;
};

}  // namespace irdist
