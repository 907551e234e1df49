#pragma once
// Absolute and monotonic time, one format for every file irdist writes: UTC as ISO 8601 with
// microseconds, "2026-12-02T06:12:03.123456Z" (frames.csv's utc_time, measure's JSON and
// estimates.csv, recording.yaml's start_time). Monotonic time is for intervals only (it never
// jumps when the wall clock is set), the UTC time for aligning with other instruments.

#include <cstdint>
#include <optional>
#include <string>

namespace irdist {

// Wall clock (system_clock): ns since the Unix epoch, UTC.
std::int64_t UtcNowNs();
// Monotonic clock (steady_clock, CLOCK_MONOTONIC on Linux): ns since an arbitrary origin (boot).
std::int64_t MonotonicNowNs();

// `unix_ns` (ns since the Unix epoch) as "YYYY-MM-DDTHH:MM:SS.ffffffZ": truncated to the
// microsecond below (also before 1970), always 27 characters for years 0000-9999.
std::string FormatUtcIso8601(std::int64_t unix_ns);
// FormatUtcIso8601(UtcNowNs()).
std::string UtcNowIso8601();

// The inverse of FormatUtcIso8601: exactly that layout (6 fraction digits, 'Z'); nullopt for any
// other text or an impossible date/time. Returns ns since the Unix epoch.
std::optional<std::int64_t> ParseUtcIso8601(const std::string& text);

}  // namespace irdist
