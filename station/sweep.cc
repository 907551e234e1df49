#include "station/sweep.h"

#include <chrono>
#include <cmath>
#include <sstream>

namespace irdist {
namespace {

// Two set-points the station cannot tell apart (its resolution is 0.01 mm, deg or mA).
bool SameCenti(double a, double b) { return std::llround(a * 100.0) == std::llround(b * 100.0); }

// Host seconds since `t0`, added to `*total_s`; returns now.
std::chrono::steady_clock::time_point AddSince(std::chrono::steady_clock::time_point t0,
                                               double* total_s) {
  const auto now = std::chrono::steady_clock::now();
  *total_s += std::chrono::duration<double>(now - t0).count();
  return now;
}

}  // namespace

bool SweepOptions::IsValid(std::string* why) const {
  if (max_retakes < 0) {
    if (why) *why = "max_retakes must be >= 0";
    return false;
  }
  if (!std::isfinite(park_slide_mm)) {
    if (why) *why = "park_slide_mm must be finite";
    return false;
  }
  return true;
}

std::string SweepResult::BriefReport() const {
  std::ostringstream out;
  out << "sweep: " << poses_done << " poses done, " << retakes << " retakes, " << reboots
      << " station reboots" << (stopped ? ", stopped early" : "");
  if (next_index >= 0) out << ", next pose index " << next_index;
  return out.str();
}

Sweep::Sweep(Station& station, SweepOptions options) : station_(station), options_(options) {
  std::string why;
  IRDIST_CHECK(options_.IsValid(&why), why);
}

void Sweep::Park() {
  station_.Off();
  if (!options_.park_at_end || !station_.homed()) return;
  StationPosition park = station_.Position();
  park.pan_deg = 0.0;
  park.tilt_deg = 0.0;
  if (options_.park_slide_mm >= 0.0) park.slide_mm = options_.park_slide_mm;
  station_.MoveTo(park);
}

// Before the first pose: every device identified, none in e-stop or moving, then homed.
void Sweep::Start() {
  station_.Identify();
  station_.CheckReadyToStart();
  if (options_.home_first || !station_.homed()) station_.Home();
}

// Sets the pose's current, then moves (the IRED's transient runs while the axes travel). A retake
// follows a device restart: it always moves and sets the current again. Returns whether it moved.
bool Sweep::GoTo(const std::vector<Pose>& poses, std::size_t i, int attempt) {
  const Pose& pose = poses[i];
  transition_.current_changed = attempt > 0;
  if (attempt > 0 || !SameCenti(pose.bias_ma, station_.setpoint_ma())) {
    station_.SetCurrent(pose.bias_ma);
    transition_.current_changed = true;
  }
  if (transition_.current_changed) {
    transition_.current_changed_at = std::chrono::steady_clock::now();
  }
  // A pose that only changes the current (or repeats) needs no move: the station is still where
  // the previous pose confirmed it.
  const bool same_place = i > 0 && attempt == 0 &&
                          SameCenti(poses[i - 1].slide_mm, pose.slide_mm) &&
                          SameCenti(poses[i - 1].pan_deg, pose.pan_deg) &&
                          SameCenti(poses[i - 1].tilt_deg, pose.tilt_deg);
  transition_.moved = !same_place;
  if (!same_place) station_.MoveTo({pose.slide_mm, pose.pan_deg, pose.tilt_deg});
  return transition_.moved;
}

SweepResult Sweep::Run(const std::vector<Pose>& poses, const PoseCallback& at_pose,
                       const std::atomic<bool>* stop, const ConfirmCallback& confirmed) {
  IRDIST_CHECK(static_cast<bool>(at_pose), "Sweep::Run needs a callback");
  SweepResult result;
  const auto t_start = std::chrono::steady_clock::now();
  try {
    for (std::size_t i = 0; i < poses.size(); ++i) {
      const Pose& pose = poses[i];
      if (stop != nullptr && stop->load()) {
        result.stopped = true;
        result.next_index = pose.index;
        break;
      }
      for (int attempt = 0;; ++attempt) {
        try {
          auto t = std::chrono::steady_clock::now();
          if (i == 0 && attempt == 0) {
            Start();
            t = AddSince(t, &result.homing_s);
          }
          GoTo(poses, i, attempt);
          AddSince(t, &result.goto_s);
          at_pose(pose, attempt);
          t = std::chrono::steady_clock::now();
          // The capture is only good if no device restarted or stopped meanwhile.
          station_.CheckAlive();
          AddSince(t, &result.check_alive_s);
          break;
        } catch (const DeviceRestarted& restarted) {
          ++result.reboots;
          if (attempt >= options_.max_retakes) throw;
          ++result.retakes;
          if (!restarted.recovered()) station_.Home();
        }
      }
      if (confirmed) confirmed(pose);
      ++result.poses_done;
    }
    Park();
    result.sweep_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count() -
        result.homing_s;
  } catch (...) {
    station_.Off();  // the original failure is the one to report
    throw;
  }
  return result;
}

}  // namespace irdist
