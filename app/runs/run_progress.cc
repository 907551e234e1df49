#include "app/runs/run_progress.h"

#include <unistd.h>

#include <algorithm>

#include "station/plan.h"

namespace irdist {

Progress::Progress(std::ostream& err, bool quiet, int total, double estimate_host_s)
    : err_(err),
      quiet_(quiet),
      tty_(isatty(STDERR_FILENO) == 1),
      total_(total),
      estimate_host_s_(estimate_host_s),
      start_(std::chrono::steady_clock::now()) {}

void Progress::Update(int done, const std::string& what) {
  if (quiet_) return;
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  // The plan's estimate per pose, corrected by the rate measured since the first pose was
  // done (before it, homing and the move from home would make the rate look slow).
  const double per_pose_plan = total_ > 0 ? estimate_host_s_ / total_ : 0.0;
  double per_pose = per_pose_plan;
  if (first_done_ < 0) {
    first_done_ = done;
    first_time_ = std::chrono::steady_clock::now();
  } else if (done > first_done_) {
    const int measured_poses = done - first_done_;
    const double measured =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - first_time_).count() /
        measured_poses;
    const double weight = std::min(1.0, measured_poses / 5.0);
    per_pose = weight * measured + (1.0 - weight) * per_pose_plan;
  }
  const double eta = per_pose * (total_ - done);
  const double fraction = total_ > 0 ? static_cast<double>(done) / total_ : 1.0;
  if (tty_) {
    constexpr int kWidth = 30;
    const int filled = static_cast<int>(fraction * kWidth);
    err_ << "\r[" << std::string(static_cast<size_t>(filled), '#')
         << std::string(static_cast<size_t>(kWidth - filled), '.') << "] " << done << "/"
         << total_ << " poses, ETA " << FormatDuration(eta) << "   " << std::flush;
    line_open_ = true;
  } else {
    err_ << "pose " << done << "/" << total_ << " (" << what << "), elapsed "
         << FormatDuration(elapsed) << ", ETA " << FormatDuration(eta) << "\n";
  }
}

void Progress::Finish() {
  if (line_open_) err_ << "\n";
  line_open_ = false;
}

}  // namespace irdist
