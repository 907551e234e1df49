#include "sim/trajectory_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <utility>
#include <vector>

#include "base/input_error.h"
#include "base/regular_file.h"
#include "base/safe_file.h"
#include "base/utc_time.h"
#include "sim/station_model_text.h"  // SplitCommas

namespace irdist::sim {
namespace {

constexpr char kHeader[] =
    "axis,unit,start_ns,start_utc,end_ns,end_utc,from,to,v0_per_s,peak_per_s,accel_per_s2,"
    "accel_s,cruise_s,decel_s";
constexpr std::size_t kColumns = 14;

std::string Number(double value) {
  char text[40];
  std::snprintf(text, sizeof(text), "%.17g", value);
  return text;
}

// One data line's reader: each field checked, errors at file:line naming the column.
struct RowReader {
  const std::string& name;
  int line;
  const std::vector<std::string>& fields;

  [[noreturn]] void Fail(const std::string& what) const {
    throw InputError(name, line, 0, what + " (a trajectory file as sim/trajectory_file.h writes "
                                           "it; docs/virtual-rig.md 'Truth of a moving target')");
  }
  double Real(std::size_t i, const char* column) const {
    const std::string& text = fields[i];
    char* end = nullptr;
    errno = 0;
    const double value = std::strtod(text.c_str(), &end);
    if (text.empty() || end != text.c_str() + text.size() || errno != 0 || !std::isfinite(value)) {
      Fail(std::string(column) + " '" + text + "' is not a finite number");
    }
    return value;
  }
  double Duration(std::size_t i, const char* column) const {
    const double value = Real(i, column);
    if (value < 0.0) Fail(std::string(column) + " must be >= 0, not " + fields[i]);
    return value;
  }
  std::uint64_t Nanoseconds(std::size_t i, const char* column) const {
    const std::string& text = fields[i];
    if (text.empty() || text.size() > 19 || text.find_first_not_of("0123456789") != text.npos) {
      Fail(std::string(column) + " '" + text + "' is not a time in ns (digits only)");
    }
    return std::strtoull(text.c_str(), nullptr, 10);
  }
  RigAxis Axis() const {
    for (int i = 0; i < kRigAxes; ++i) {
      const RigAxis axis = static_cast<RigAxis>(i);
      if (fields[0] != RigAxisName(axis)) continue;
      if (fields[1] != RigAxisUnit(axis)) {
        Fail("unit '" + fields[1] + "' of axis " + fields[0] + ": must be " + RigAxisUnit(axis));
      }
      return axis;
    }
    Fail("axis '" + fields[0] + "' is not slide, pan or tilt");
  }
  void Utc(std::size_t i, const char* column) const {
    if (!ParseUtcIso8601(fields[i])) {
      Fail(std::string(column) + " '" + fields[i] + "' is not UTC as 2026-12-02T06:12:03.123456Z");
    }
  }
  MotionProfile Profile() const {
    MotionProfile p;
    p.start_s = NsToSimTime(Nanoseconds(2, "start_ns"));
    Nanoseconds(4, "end_ns");
    Utc(3, "start_utc");
    Utc(5, "end_utc");
    p.from = Real(6, "from");
    p.to = Real(7, "to");
    p.v0 = Duration(8, "v0_per_s");
    p.vp = Duration(9, "peak_per_s");
    p.accel = Real(10, "accel_per_s2");
    if (!(p.accel > 0.0)) Fail("accel_per_s2 must be > 0, not " + fields[10]);
    p.t_acc = Duration(11, "accel_s");
    p.t_cruise = Duration(12, "cruise_s");
    p.t_dec = Duration(13, "decel_s");
    return p;
  }
};

}  // namespace

std::string TrajectoryCsvHeader() { return kHeader; }

std::string TrajectoryCsvRow(RigAxis axis, const MotionProfile& p,
                             const std::function<std::int64_t(double)>& utc_ns) {
  std::string row = std::string(RigAxisName(axis)) + "," + RigAxisUnit(axis);
  for (const double t_s : {p.start_s, p.EndS()}) {
    row += "," + std::to_string(SimTimeToNs(t_s)) + "," + FormatUtcIso8601(utc_ns(t_s));
  }
  for (const double value : {p.from, p.to, p.v0, p.vp, p.accel, p.t_acc, p.t_cruise, p.t_dec}) {
    row += "," + Number(value);
  }
  return row;
}

TrajectoryLog::TrajectoryLog(std::string path, std::function<std::int64_t(double)> utc_ns)
    : path_(std::move(path)), utc_ns_(std::move(utc_ns)) {
  std::string why;
  fd_ = CreateNewFile(path_, 0600, &why);
  if (fd_ < 0) {
    throw TrajectoryFileError("trajectory file " + path_ + ": " + why +
                              " (give a new file's path in a folder you may write)");
  }
  const std::string header = TrajectoryCsvHeader() + "\n";
  if (::write(fd_, header.data(), header.size()) != static_cast<ssize_t>(header.size())) {
    const std::string reason = std::strerror(errno);
    ::close(fd_);
    throw TrajectoryFileError("trajectory file " + path_ + ": cannot write its header: " + reason +
                              " (free disk space, or give another folder)");
  }
}

TrajectoryLog::~TrajectoryLog() {
  if (fd_ >= 0) ::close(fd_);  // a log: nothing to report at the end
}

void TrajectoryLog::Append(RigAxis axis, const MotionProfile& profile) {
  const std::string row = TrajectoryCsvRow(axis, profile, utc_ns_) + "\n";
  std::lock_guard<std::mutex> lock(mutex_);
  if (!error_.empty()) return;
  std::size_t done = 0;
  while (done < row.size()) {
    const ssize_t n = ::write(fd_, row.data() + done, row.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      error_ = "trajectory file " + path_ + ": a row was not written (" +
               (n < 0 ? std::strerror(errno) : "no progress") +
               "); the rows after it are missing (free disk space and restart the rig)";
      return;
    }
    done += static_cast<std::size_t>(n);
  }
}

std::string TrajectoryLog::Error() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return error_;
}

Trajectory ParseTrajectoryCsv(const std::string& text, const std::string& name) {
  // A last line without its newline is a row being written by a running rig: not read yet.
  std::istringstream in(text.substr(0, text.rfind('\n') + 1));
  std::string line;
  if (!std::getline(in, line) || line != kHeader) {
    throw InputError(name, 1, 0, std::string("the header must be '") + kHeader + "'");
  }
  Trajectory trajectory;
  std::array<double, kRigAxes> last_start_s{-1.0, -1.0, -1.0};
  for (int number = 2; std::getline(in, line); ++number) {
    const std::vector<std::string> fields = SplitCommas(line);
    const RowReader row{name, number, fields};
    if (line.find_first_of(" \t\r") != std::string::npos) row.Fail("has a space or tab");
    if (fields.size() != kColumns) {
      row.Fail("has " + std::to_string(fields.size()) + " fields, not " +
               std::to_string(kColumns));
    }
    const RigAxis axis = row.Axis();
    const MotionProfile profile = row.Profile();
    double& last = last_start_s[static_cast<int>(axis)];
    if (profile.start_s < last) row.Fail("start_ns goes back in time for axis " + fields[0]);
    last = profile.start_s;
    trajectory.Add(axis, profile);
  }
  return trajectory;
}

Trajectory ReadTrajectoryFile(const std::string& path) {
  std::string text, why;
  if (!ReadRegularFile(path, kMaxInputTextBytes, &text, &why)) {
    throw InputError(path, 0, 0, why + " (give the trajectory file the virtual rig wrote)");
  }
  return ParseTrajectoryCsv(text, path);
}

}  // namespace irdist::sim
