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

#include <chrono>
#include <cmath>
#include <cstdint>
#include <functional>
#include <mutex>
#include <vector>

#include "base/pi.h"

namespace irdist::sim {

class SimClock {
 public:
  explicit SimClock(double time_scale = 1.0)
      : time_scale_(time_scale), start_(std::chrono::steady_clock::now()) {}
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

 private:
  double time_scale_;
  std::chrono::steady_clock::time_point start_;
};

// The station's physical state at one instant, as the camera sees it.
struct PoseState {
  double slide_mm = 2000.0;  // camera-to-IRED distance along the slide (the ground truth d)
  double pan_deg = 0.0;
  double tilt_deg = 0.0;
  bool moving = false;       // some axis is in motion (frames taken now are smeared/wrong)
  double bias_ma = 0.0;      // IRED current as set (0 = off)
  double ThetaDeg() const {
    constexpr double kDeg = kPi / 180.0;
    const double c = std::cos(pan_deg * kDeg) * std::cos(tilt_deg * kDeg);
    return std::acos(std::fmin(1.0, std::fmax(-1.0, c))) / kDeg;
  }
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
  std::vector<CurrentStep> history_;
  std::uint64_t trigger_pulses_ = 0;
  std::function<void()> trigger_sink_;
};

}  // namespace irdist::sim
