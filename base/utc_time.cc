#include "base/utc_time.h"

#include <chrono>
#include <cstdio>
#include <ctime>

namespace irdist {

namespace {

constexpr std::int64_t kNsPerUs = 1000;
constexpr std::int64_t kUsPerSecond = 1000000;

// Floor division (C++ rounds toward zero; a time before 1970 must round down).
std::int64_t FloorDiv(std::int64_t value, std::int64_t divisor) {
  const std::int64_t q = value / divisor;
  return (value % divisor != 0 && value < 0) ? q - 1 : q;
}

}  // namespace

std::int64_t UtcNowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

std::int64_t MonotonicNowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

std::string FormatUtcIso8601(std::int64_t unix_ns) {
  const std::int64_t us = FloorDiv(unix_ns, kNsPerUs);
  const std::int64_t seconds = FloorDiv(us, kUsPerSecond);
  const std::int64_t fraction_us = us - seconds * kUsPerSecond;
  const auto t = static_cast<std::time_t>(seconds);
  std::tm utc{};
  if (gmtime_r(&t, &utc) == nullptr) return "";  // beyond the platform's time_t range
  char out[64];
  std::snprintf(out, sizeof(out), "%04d-%02d-%02dT%02d:%02d:%02d.%06lldZ", utc.tm_year + 1900,
                utc.tm_mon + 1, utc.tm_mday, utc.tm_hour, utc.tm_min, utc.tm_sec,
                static_cast<long long>(fraction_us));
  return out;
}

std::string UtcNowIso8601() { return FormatUtcIso8601(UtcNowNs()); }

std::optional<std::int64_t> ParseUtcIso8601(const std::string& text) {
  // Fixed layout: the digits checked one by one (sscanf alone would accept signs and spaces).
  static const char kLayout[] = "dddd-dd-ddTdd:dd:dd.ddddddZ";
  if (text.size() != sizeof(kLayout) - 1) return std::nullopt;
  for (size_t i = 0; i < text.size(); ++i) {
    const bool digit = text[i] >= '0' && text[i] <= '9';
    if (kLayout[i] == 'd' ? !digit : text[i] != kLayout[i]) return std::nullopt;
  }
  std::tm utc{};
  long long fraction_us = 0;
  if (std::sscanf(text.c_str(), "%4d-%2d-%2dT%2d:%2d:%2d.%6lld", &utc.tm_year, &utc.tm_mon,
                  &utc.tm_mday, &utc.tm_hour, &utc.tm_min, &utc.tm_sec, &fraction_us) != 7) {
    return std::nullopt;
  }
  utc.tm_year -= 1900;
  utc.tm_mon -= 1;
  const std::int64_t seconds = timegm(&utc);
  // timegm normalizes out-of-range fields (Feb 30 -> Mar 2): formatting back must give the text.
  const std::int64_t ns = (seconds * kUsPerSecond + fraction_us) * kNsPerUs;
  if (FormatUtcIso8601(ns) != text) return std::nullopt;
  return ns;
}

}  // namespace irdist
