#include "station/sweep.h"

#include <cmath>
#include <sstream>

namespace irdist {
namespace {

// Two set-points the station cannot tell apart (its resolution is 0.01 mm, deg or mA).
bool SameCenti(double a, double b) { return std::llround(a * 100.0) == std::llround(b * 100.0); }

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

Sweep::Sweep(StationClient& client, SweepOptions options) : client_(client), options_(options) {
  std::string why;
  IRDIST_CHECK(options_.IsValid(&why), why);
}

void Sweep::Park() {
  client_.SetCurrent(0.0);
  if (!options_.park_at_end || !client_.homed()) return;
  StationPosition park = client_.Position();
  park.pan_deg = 0.0;
  park.tilt_deg = 0.0;
  if (options_.park_slide_mm >= 0.0) park.slide_mm = options_.park_slide_mm;
  client_.MoveTo(park);
}

SweepResult Sweep::Run(const std::vector<SweepPose>& poses, const PoseCallback& at_pose,
                       const std::atomic<bool>* stop) {
  IRDIST_CHECK(static_cast<bool>(at_pose), "Sweep::Run needs a callback");
  SweepResult result;
  const std::uint64_t reboots_before = client_.stats().reboots;
  try {
    for (std::size_t i = 0; i < poses.size(); ++i) {
      const SweepPose& pose = poses[i];
      if (stop != nullptr && stop->load()) {
        result.stopped = true;
        result.next_index = pose.index;
        break;
      }
      for (int attempt = 0;; ++attempt) {
        try {
          if (i == 0 && attempt == 0) {
            client_.Identify();
            const StationState s = client_.Status().state;
            if (options_.home_first || s == StationState::kUnhomed || !client_.homed()) {
              client_.Home();
            }
          }
          // Current first: the IRED's thermal transient then overlaps the move. A retake follows
          // a reboot, whose recovery has just restored the current.
          transition_.current_changed = attempt > 0;
          if (!SameCenti(pose.bias_ma, client_.current_setpoint_ma())) {
            client_.SetCurrent(pose.bias_ma);
            transition_.current_changed = true;
          }
          if (transition_.current_changed) {
            transition_.current_changed_at = std::chrono::steady_clock::now();
          }
          // A pose that only changes the current (or repeats) needs no move: the station is
          // still where the previous pose confirmed it (a retake always moves again).
          const bool same_place = i > 0 && attempt == 0 &&
                                  SameCenti(poses[i - 1].slide_mm, pose.slide_mm) &&
                                  SameCenti(poses[i - 1].pan_deg, pose.pan_deg) &&
                                  SameCenti(poses[i - 1].tilt_deg, pose.tilt_deg);
          transition_.moved = !same_place;
          if (!same_place) client_.MoveTo({pose.slide_mm, pose.pan_deg, pose.tilt_deg});
          at_pose(pose, attempt);
          // The capture is only good if the station did not reboot meanwhile.
          client_.Status();
          break;
        } catch (const StationRebooted&) {
          if (attempt >= options_.max_retakes) throw;
          ++result.retakes;
        }
      }
      ++result.poses_done;
    }
    result.reboots = static_cast<std::size_t>(client_.stats().reboots - reboots_before);
    Park();
  } catch (...) {
    try {
      client_.SetCurrent(0.0);
    } catch (const Error&) {
      // The original failure is the one to report.
    }
    throw;
  }
  return result;
}

}  // namespace irdist
