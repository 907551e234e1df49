#pragma once
// Test-only: the station model (sim/station_model.h) acting on a World without its pty: the
// effects bound to the World as the station emulator binds them, and optionally a thread that
// advances the model in the World's simulated time (as the emulator's loop does).

#include <atomic>
#include <chrono>
#include <mutex>
#include <string>
#include <thread>

#include "sim/station_model.h"
#include "sim/world.h"

namespace irdist::sim::testing {

struct WorldEffects : StationEffects {
  explicit WorldEffects(World& w) : world(w) {}
  void SetPose(double slide_mm, double pan_deg, double tilt_deg, bool moving) override {
    world.SetPose(slide_mm, pan_deg, tilt_deg, moving);
  }
  void SetAxisMotion(RigAxis axis, const MotionProfile& profile) override {
    world.SetAxisMotion(axis, profile);
  }
  void SetCurrent(double bias_ma) override { world.SetCurrent(bias_ma); }
  void FireTrigger() override { world.FireTrigger(); }
  World& world;
};

// A slide of 0.5 m/s cruise and 1 m/s^2 ramps; the move 1500 -> 3000 mm started at tau = 0 on
// it, written out by hand (accelerate 0.5 s, cruise 2.5 s, stop 0.5 s): position and velocity.
inline EmulatorOptions HalfMetrePerSecond() {
  EmulatorOptions options;
  options.slide.speed = 500.0;   // mm/s
  options.slide.accel = 1000.0;  // mm/s^2: 0.5 s to cruise, 125 mm
  return options;
}
inline double ExpectedSlideMm(double tau) {
  if (tau <= 0.0) return 1500.0;
  if (tau < 0.5) return 1500.0 + 500.0 * tau * tau;
  if (tau < 3.0) return 1625.0 + 500.0 * (tau - 0.5);
  if (tau < 3.5) return 2875.0 + 500.0 * (tau - 3.0) - 500.0 * (tau - 3.0) * (tau - 3.0);
  return 3000.0;
}
inline double ExpectedSlideMmS(double tau) {
  if (tau <= 0.0 || tau >= 3.5) return 0.0;
  if (tau < 0.5) return 1000.0 * tau;
  if (tau < 3.0) return 500.0;
  return 500.0 - 1000.0 * (tau - 3.0);
}

// The model in the World's time, advanced every 0.5 ms of host time by its own thread.
class StationOnWorld {
 public:
  StationOnWorld(World& world, const EmulatorOptions& options)
      : world_(world), effects_(world), model_(effects_, options) {
    model_.PowerOn(world_.clock().Now());
    thread_ = std::thread([this] {
      while (!stop_) {
        {
          std::lock_guard<std::mutex> lock(mutex_);
          model_.Advance(world_.clock().Now());
        }
        std::this_thread::sleep_for(std::chrono::microseconds(500));
      }
    });
  }
  ~StationOnWorld() {
    stop_ = true;
    thread_.join();
  }
  // Executes `command` now; *at_s (if given) is the simulated time it was executed at.
  std::string Do(const std::string& command, double* at_s = nullptr) {
    std::lock_guard<std::mutex> lock(mutex_);
    const double now_s = world_.clock().Now();
    if (at_s != nullptr) *at_s = now_s;
    return model_.Execute(command, now_s);
  }
  // Waits (host time, at most `limit`) until STAT? starts with `state`.
  bool WaitFor(const std::string& state, std::chrono::milliseconds limit) {
    const auto until = std::chrono::steady_clock::now() + limit;
    while (std::chrono::steady_clock::now() < until) {
      if (Do("STAT?").rfind("OK " + state, 0) == 0) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    return false;
  }

 private:
  World& world_;
  WorldEffects effects_;
  StationModel model_;
  std::mutex mutex_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace irdist::sim::testing
