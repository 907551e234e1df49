#pragma once
// The station's trajectory as a CSV file (docs/virtual-rig.md, "Truth of a moving target"): one
// row per motion profile an axis started (a move, a stop, a halt, a power-up at rest), written as
// the profile starts, so a reader finds every move up to now. Times are on the camera's clock:
// `*_ns` the simulated time in ns, the same clock as the frames' GigE Vision timestamps
// (sim/camera_server.h), and `*_utc` the host's UTC time of that instant (base/utc_time.h). The
// profile's numbers are written with 17 significant digits, so the reader rebuilds the exact
// trajectory (sim/trajectory.h) and any frame's truth from its timestamp and exposure.
//
// Columns: axis,unit,start_ns,start_utc,end_ns,end_utc,from,to,v0_per_s,peak_per_s,accel_per_s2,
//          accel_s,cruise_s,decel_s

#include <cstdint>
#include <functional>
#include <mutex>
#include <string>

#include "base/check.h"
#include "sim/trajectory.h"

namespace irdist::sim {

// The trajectory file cannot be created or written. Names the file and the fix.
class TrajectoryFileError : public Error {
 public:
  using Error::Error;
};

// The header line (without its newline) and one row (without its newline). `utc_ns` maps a
// simulated time to the host's UTC time (ns since the Unix epoch).
std::string TrajectoryCsvHeader();
std::string TrajectoryCsvRow(RigAxis axis, const MotionProfile& profile,
                             const std::function<std::int64_t(double)>& utc_ns);

// The log the World appends to: created new (never a planted name or link, base/safe_file.h),
// header first, then one row per profile as it starts.
class TrajectoryLog {
 public:
  // Throws TrajectoryFileError when `path` exists or cannot be created.
  TrajectoryLog(std::string path, std::function<std::int64_t(double)> utc_ns);
  ~TrajectoryLog();
  TrajectoryLog(const TrajectoryLog&) = delete;
  TrajectoryLog& operator=(const TrajectoryLog&) = delete;

  // Appends one row. Never throws (called from the station's thread): the first failure is kept,
  // later rows are not written, and Error() says so.
  void Append(RigAxis axis, const MotionProfile& profile);
  const std::string& path() const { return path_; }
  std::string Error() const;  // "" while every row was written

 private:
  std::string path_;
  std::function<std::int64_t(double)> utc_ns_;
  mutable std::mutex mutex_;
  int fd_ = -1;
  std::string error_;
};

// Reads a trajectory file: every row checked (axis and its unit, integer times, finite numbers,
// durations >= 0, rows per axis in time order). Throws InputError (base/input_error.h) naming the
// file, the line and what is wrong.
Trajectory ReadTrajectoryFile(const std::string& path);
// The same from the file's text (`name` for the errors).
Trajectory ParseTrajectoryCsv(const std::string& text, const std::string& name);

}  // namespace irdist::sim
