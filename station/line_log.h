#pragma once
// The station's line log: every raw line sent and received, one per log line, stamped with the
// host's monotonic clock (seconds since the log was opened), e.g.
//   12.004531 > #17 MOVE 250000,1000,0*3A
//   12.006102 < #17 OK*5C
// Non-printable bytes are written as \xHH so that a garbled reply stays readable. Thread-safe.

#include <chrono>
#include <fstream>
#include <mutex>
#include <string>
#include <string_view>

namespace irdist {

class LineLog {
 public:
  // Opens (truncates) `path`. Throws LinkError if the file cannot be created.
  explicit LineLog(const std::string& path);
  LineLog(const LineLog&) = delete;
  LineLog& operator=(const LineLog&) = delete;

  void Sent(std::string_view line) { Write('>', line); }
  void Received(std::string_view line) { Write('<', line); }
  // A remark from the client (a timeout, a retry, a reboot), marked '#'.
  void Note(std::string_view text) { Write('#', text); }
  const std::string& path() const { return path_; }

 private:
  void Write(char direction, std::string_view line);
  std::string path_;
  std::mutex mutex_;
  std::ofstream out_;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace irdist
