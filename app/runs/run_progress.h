#pragma once
// A live run's progress on stderr (calibrate, validate, plan --suggest's probe): a bar with the
// ETA on a terminal, one log line per pose otherwise. app/runs/run.cc updates it as each bracket
// is committed.

#include <chrono>
#include <ostream>
#include <string>

namespace irdist {

// Progress on stderr: a bar with ETA on a terminal, one log line per pose otherwise.
class Progress {
 public:
  // `total` poses planned to take `estimate_host_s` host seconds; `quiet` prints nothing.
  Progress(std::ostream& err, bool quiet, int total, double estimate_host_s);

  // `done` poses of the total are committed, the last one `what` ("d 1500 mm, ...").
  void Update(int done, const std::string& what);
  // Ends the terminal's bar line (before anything else is printed).
  void Finish();

 private:
  std::ostream& err_;
  bool quiet_;
  bool tty_;
  int total_;
  double estimate_host_s_;
  std::chrono::steady_clock::time_point start_;
  int first_done_ = -1;  // poses done at the first update, and when
  std::chrono::steady_clock::time_point first_time_;
  bool line_open_ = false;
};

}  // namespace irdist
