#include "station/line_log.h"

#include <cstdio>

#include "station/transport.h"

namespace irdist {

LineLog::LineLog(const std::string& path)
    : path_(path), out_(path, std::ios::trunc), start_(std::chrono::steady_clock::now()) {
  if (!out_) {
    throw LinkError("cannot create the station line log", path,
                    "check that the run's folder exists and is writable");
  }
}

void LineLog::Write(char direction, std::string_view line) {
  const std::chrono::duration<double> t = std::chrono::steady_clock::now() - start_;
  std::string text;
  text.reserve(line.size() + 24);
  char stamp[32];
  std::snprintf(stamp, sizeof(stamp), "%.6f %c ", t.count(), direction);
  text += stamp;
  for (char c : line) {
    const auto u = static_cast<unsigned char>(c);
    if (u >= 0x20 && u < 0x7F && c != '\\') {
      text.push_back(c);
    } else {
      char hex[8];
      std::snprintf(hex, sizeof(hex), "\\x%02X", u);
      text += hex;
    }
  }
  text.push_back('\n');
  std::lock_guard<std::mutex> lock(mutex_);
  out_ << text;
  out_.flush();
}

}  // namespace irdist
