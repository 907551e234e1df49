#pragma once
// What `irdist measure --track` shows (docs/measure.md "Tracking"): one line per frame (mode
// "track": the frame's own estimate on measure's JSON schema, the filter's smoothed distance and
// velocity beside it, the frame counters) and one per interleaved bracket (mode "bracket":
// measure's bracket line with the check against the track), and the run's summary.

#include <cstdint>
#include <string>
#include <vector>

#include "app/live/frame_grabber.h"
#include "app/live/measure_output.h"
#include "estimator/track_filter.h"

namespace irdist {

// A bracket's cross-check against the track: the filter's distance carried to the bracket's time
// and the bracket's own, their difference in combined standard errors.
struct TrackCheck {
  bool assessed = false;  // the track had started and both have standard errors
  double track_d_mm = NAN, track_se_mm = NAN;
  double z = NAN;  // (bracket d - track d) / sqrt(se_bracket^2 + se_track^2)
  double z_limit = 3.0;
  bool agree = true;  // |z| <= z_limit (true when not assessed)
};

struct TrackSample {
  MeasureSample estimate;   // mode "track" (one frame) or "bracket" (a check)
  std::string acquisition;  // how the camera runs, e.g. "triggered"
  std::int64_t frame = -1;  // the frame's number among those received (-1: a bracket)
  std::uint64_t camera_frame_id = 0;
  double exposure_ms = NAN;
  // CPU time (ms) the estimator's thread spent on this frame: its features (with the blob fit)
  // and estimate (NaN for a bracket).
  double cpu_ms = NAN;
  bool filtered = false;   // the filter saw this frame (`track` in the JSON)
  TrackState filter;       // its state after the frame (1 axis: the distance)
  TrackCounters counters;  // the run's frame counters after this line
  TrackCheck check;        // a bracket's cross-check
};

// The line's JSON object: MeasureJson of the estimate with the track's keys added.
std::string TrackJson(const TrackSample& s);
// The text line: measure's line, the filtered distance and velocity, the counters when not 0.
std::string TrackLine(const TrackSample& s);
// The check of a bracket at time_s against the track's last state (its velocity carries the
// distance over the gap; the se adds the velocity's over it).
TrackCheck CheckAgainstTrack(const TrackState& last, bool track_started, double bracket_time_s,
                             const MeasureSample& bracket);

// The run's summary: rates (estimates against the camera's frames), latency quantiles, counters,
// the distance's mean and sd, and the bracket checks.
class TrackStats {
 public:
  void Add(const TrackSample& s);
  // `wall_s`: the run's host seconds; `counters`: the grabber's at the end.
  std::string Report(double wall_s, const TrackCounters& counters) const;
  int lines() const { return lines_; }
  // The latency's quantile q (ms) over the track lines (NaN without any).
  double LatencyQuantileMs(double q) const;

 private:
  int lines_ = 0, frames_ = 0, estimated_ = 0, checks_ = 0, disagree_ = 0, suspect_ = 0;
  double d_sum_ = 0.0, d_sum2_ = 0.0, se_sum2_ = 0.0;
  double latency_max_ms_ = 0.0;
  // Latency histogram in 10 us bins up to 1 s (the last bin holds the rest): quantiles in fixed
  // memory over any run length.
  std::vector<std::int64_t> latency_bins_ = std::vector<std::int64_t>(100001, 0);
};

}  // namespace irdist
