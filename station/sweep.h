#pragma once
// The sweep runner: moves the composed station (station/station.h) through a list of poses and
// calls back at each settled pose (the app captures frames there; station/ never sees the camera).
// It recovers from device restarts by retaking the pose, and honours a stop flag (Ctrl-C): the
// pose in flight is finished, then the station is parked with the IRED off.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "station/pose.h"
#include "station/station.h"

namespace irdist {

struct SweepOptions {
  bool home_first = true;       // home before the first pose (always done if unhomed)
  int max_retakes = 3;          // retakes of one pose after station reboots, then give up
  bool park_at_end = true;      // at the end (or on stop): pan = tilt = 0, slide per below
  double park_slide_mm = -1.0;  // slide position when parking; < 0 leaves the slide where it is
  bool IsValid(std::string* why) const;
};

struct SweepResult {
  std::size_t poses_done = 0;    // poses whose callback completed on a stable station
  std::size_t retakes = 0;       // poses taken again after a reboot
  std::size_t reboots = 0;       // device restarts seen
  bool stopped = false;          // the stop flag ended the sweep early
  std::int64_t next_index = -1;  // index of the first pose not done (-1 when all are done)
  // Host time, s: identify and home (Start), then the sweep from the end of homing to the end of
  // parking; inside the sweep, the current set + move of each pose (GoTo) and the station's
  // alive checks after each capture.
  double homing_s = 0.0;
  double sweep_s = 0.0;
  double goto_s = 0.0;
  double check_alive_s = 0.0;
  std::string BriefReport() const;
};

// Called at each settled pose with the IRED at pose.bias_ma (set before the move, so that its
// thermal transient runs while the axes travel: see Sweep::transition()). `attempt` is 0
// the first time; a retake after a device restart calls again with attempt > 0, and whatever the
// caller captured for this pose in earlier attempts must be discarded.
// Exceptions thrown here end the sweep (after the IRED is switched off) and propagate.
using PoseCallback = std::function<void(const Pose& pose, int attempt)>;
// Called once a pose's capture is confirmed: every device was seen alive and unchanged
// (Station::CheckAlive) AFTER the pose's callback returned, and BEFORE anything moves again. The
// caller commits what it captured here: a refused or failed next move, an e-stop, a silent device
// or a kill during the next move can no longer lose it.
using ConfirmCallback = std::function<void(const Pose& pose)>;

class Sweep {
 public:
  // `station` must outlive the sweep.
  explicit Sweep(Station& station, SweepOptions options = {});

  // Runs the poses in order. `stop` (may be null) is polled between poses. On every exit the
  // IRED is switched off; on normal end or stop the station is parked (options). Throws
  // DeviceError, LinkError, StationNotReadyError, DeviceRestarted (after max_retakes), or what
  // the callbacks throw.
  SweepResult Run(const std::vector<Pose>& poses, const PoseCallback& at_pose,
                  const std::atomic<bool>* stop = nullptr,
                  const ConfirmCallback& confirmed = {});

  // How the station reached the pose of the callback in progress: whether the axes moved and the
  // current changed (a retake after a reboot counts as both), and when the current was set (host
  // clock). A caller that waits for the IRED's transient waits only what is left of it.
  struct Transition {
    bool moved = false;
    bool current_changed = false;
    std::chrono::steady_clock::time_point current_changed_at{};
  };
  const Transition& transition() const { return transition_; }

 private:
  void Park();
  void Start();
  bool GoTo(const std::vector<Pose>& poses, std::size_t i, int attempt);
  Station& station_;
  SweepOptions options_;
  Transition transition_;
};

}  // namespace irdist
