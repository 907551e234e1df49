#pragma once
// The virtual rig's one physical world, shared by its two faces: the station emulator (which moves
// the axes, sets the IRED current and pulses the trigger line) and the GigE camera (which renders
// what the sensor sees when a frame is exposed). Both sides only talk through this class, so the
// camera never knows about the serial protocol and the emulator never knows about pixels.
//
// Time is simulated time in seconds since the world was created, running `time_scale` times faster
// than the host's steady clock (1 = real time). Every physical duration (motion, settle, exposure,
// readout, thermal drift) is expressed in simulated seconds.
//
// Orientation convention: the IRED sits on a pan-tilt platform; at pan = tilt = 0 its emission
// axis points at the camera. The orientation angle theta between the emission axis and the line
// to the camera is cos(theta) = cos(pan) * cos(tilt).

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <vector>

#include "base/utc_time.h"
#include "sim/trajectory.h"
#include "sim/trajectory_file.h"
#include "base/pi.h"

namespace irdist::sim {

class SimClock {
 public:
  explicit SimClock(double time_scale = 1.0)
      : time_scale_(time_scale),
        start_(std::chrono::steady_clock::now()),
        utc_start_ns_(UtcNowNs()) {}
  double time_scale() const { return time_scale_; }
  // Simulated seconds since construction.
  double Now() const {
    const std::chrono::duration<double> host = std::chrono::steady_clock::now() - start_;
    return host.count() * time_scale_;
  }
  // Host duration that a simulated duration takes.
  std::chrono::duration<double> HostDuration(double sim_s) const {
    return std::chrono::duration<double>(sim_s / time_scale_);
  }
  // The host's UTC time (ns since the Unix epoch) of simulated time sim_s: the wall clock read
  // when the clock started plus the host time that sim_s took.
  std::int64_t UtcNs(double sim_s) const {
    return utc_start_ns_ + static_cast<std::int64_t>(std::llround(sim_s / time_scale_ * 1e9));
  }

 private:
  double time_scale_;
  std::chrono::steady_clock::time_point start_;
  std::int64_t utc_start_ns_;
};

// The station's physical state at one instant, as the camera sees it.
struct PoseState {
  double slide_mm = 2000.0;  // camera-to-IRED distance along the slide (the ground truth d)
  double pan_deg = 0.0;
  double tilt_deg = 0.0;
  bool moving = false;       // some axis is in motion (frames taken now are smeared/wrong)
  double bias_ma = 0.0;      // IRED current as set (0 = off)
  double ThetaDeg() const { return ThetaDegOf(pan_deg, tilt_deg); }
};

// One change of the IRED current, for the thermal model (self-heating integrates this history).
struct CurrentStep {
  double sim_time_s = 0.0;
  double bias_ma = 0.0;
};

class World {
 public:
  explicit World(double time_scale = 1.0) : clock_(time_scale) {}
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  const SimClock& clock() const { return clock_; }

  // --- written by the station emulator ---------------------------------------------------------
  void SetPose(double slide_mm, double pan_deg, double tilt_deg, bool moving) {
    std::lock_guard<std::mutex> lock(mutex_);
    pose_.slide_mm = slide_mm;
    pose_.pan_deg = pan_deg;
    pose_.tilt_deg = tilt_deg;
    pose_.moving = moving;
  }
  // An axis starts following `profile` (sim/motion_profile.h) at profile.start_s: the exact
  // trajectory PoseAt() and TruthAt() read, appended to the trajectory file when one is logged.
  void SetAxisMotion(RigAxis axis, const MotionProfile& profile) {
    std::lock_guard<std::mutex> lock(mutex_);
    trajectory_.Add(axis, profile);
    if (log_) log_->Append(axis, profile);
  }
  // Logs every profile from now on to a new CSV file at `path` (sim/trajectory_file.h), starting
  // with the profiles each axis follows now. Throws TrajectoryFileError.
  void LogTrajectory(const std::string& path) {
    auto log = std::make_unique<TrajectoryLog>(
        path, [this](double sim_s) { return clock_.UtcNs(sim_s); });
    std::lock_guard<std::mutex> lock(mutex_);
    for (int i = 0; i < kRigAxes; ++i) {
      const RigAxis axis = static_cast<RigAxis>(i);
      if (trajectory_.Has(axis)) log->Append(axis, trajectory_.Profiles(axis).back());
    }
    log_ = std::move(log);
  }
  // The trajectory file's path and its first write error ("" when none, or when not logged).
  std::string TrajectoryLogPath() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return log_ ? log_->path() : std::string();
  }
  std::string TrajectoryLogError() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return log_ ? log_->Error() : std::string();
  }
  void SetCurrent(double bias_ma) {
    std::lock_guard<std::mutex> lock(mutex_);
    pose_.bias_ma = bias_ma;
    history_.push_back({clock_.Now(), bias_ma});
  }
  // One pulse on the trigger line (the camera's Line1 input). Called from the emulator's thread.
  void FireTrigger() {
    std::function<void()> sink;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      ++trigger_pulses_;
      sink = trigger_sink_;
    }
    if (sink) sink();
  }

  // --- read by the camera ----------------------------------------------------------------------
  PoseState Pose() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return pose_;
  }
  // The pose at simulated time t_s: the axes from the trajectory where the station gave their
  // profiles (exact at any instant), else as last set by SetPose; the current as set at t_s;
  // `moving` as now.
  PoseState PoseAt(double t_s) const {
    std::lock_guard<std::mutex> lock(mutex_);
    PoseState pose = pose_;
    const TrajectoryPoint point = trajectory_.At(t_s);
    if (trajectory_.Has(RigAxis::kSlide)) pose.slide_mm = point.slide_mm;
    if (trajectory_.Has(RigAxis::kPan)) pose.pan_deg = point.pan_deg;
    if (trajectory_.Has(RigAxis::kTilt)) pose.tilt_deg = point.tilt_deg;
    // The current set last at or before t_s.
    const auto after = std::upper_bound(
        history_.begin(), history_.end(), t_s,
        [](double t, const CurrentStep& step) { return t < step.sim_time_s; });
    if (after != history_.begin()) pose.bias_ma = (after - 1)->bias_ma;
    return pose;
  }
  // The trajectory's point at t_s (known = false when some axis has no profile: a station of
  // devices, or a test that only calls SetPose).
  TrajectoryPoint TruthAt(double t_s) const {
    std::lock_guard<std::mutex> lock(mutex_);
    return trajectory_.At(t_s);
  }
  std::vector<CurrentStep> CurrentHistory() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return history_;
  }
  std::uint64_t TriggerPulses() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return trigger_pulses_;
  }
  // The camera registers what a Line1 pulse does (nullptr to disconnect).
  void SetTriggerSink(std::function<void()> sink) {
    std::lock_guard<std::mutex> lock(mutex_);
    trigger_sink_ = std::move(sink);
  }

 private:
  SimClock clock_;
  mutable std::mutex mutex_;
  PoseState pose_;
  Trajectory trajectory_;
  std::unique_ptr<TrajectoryLog> log_;
  std::vector<CurrentStep> history_;
  std::uint64_t trigger_pulses_ = 0;
  std::function<void()> trigger_sink_;
};

}  // namespace irdist::sim
