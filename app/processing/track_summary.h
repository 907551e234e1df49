#pragma once
// A track run's figures (docs/recipes.md "Track recipes", docs/measure.md "Tracking"): every
// frame's row of track.csv (its estimate and the constant-velocity filter's state), its truth
// (the virtual rig's mid-exposure trajectory, or on a real rig the commanded profile with its
// stated uncertainty) and the one-frame bound at that truth; from them the per-frame distance
// errors against the truth and against the bound, and the filter's velocity against the truth's
// on each segment's cruise. summary.yaml of a track run is TrackSummaryYaml.

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace irdist {

// One frame as track.csv holds it.
struct TrackFrameRow {
  std::int64_t frame = 0;              // its number among the frames received (from 0)
  std::uint64_t camera_frame_id = 0;   // the camera's block id
  std::uint64_t camera_timestamp_ns = 0;  // the camera's timestamp (0: none)
  std::int64_t utc_ns = 0;             // arrival on the host's wall clock
  double exposure_ms = NAN;
  int segment = -1;                    // the profile's segment under way (-1: none yet)
  bool ok = false;                     // the frame gave an estimate
  double d_mm = NAN, d_se_mm = NAN, theta_deg = NAN;
  bool filtered = false;               // the filter took it
  double track_d_mm = NAN, track_d_se_mm = NAN;
  double v_mm_per_s = NAN, v_se_mm_per_s = NAN;
  std::string flags;                   // the quality flags, space separated ("" none)
};

// track.csv's header line and one row (no line end), in the same column order.
std::string TrackCsvHeader();
std::string TrackCsvRow(const TrackFrameRow& row);

// One frame's truth and bound.
struct TrackTruth {
  bool known = false;
  double d_mm = NAN;           // the IRED's distance at the middle of the exposure
  double v_mm_per_s = NAN;     // its velocity then (signed)
  double sd_mm = 0.0;          // the truth's own standard uncertainty (0 on the virtual rig)
  double cruise_s = NAN;       // seconds since the slide's cruise began (NaN: not cruising)
  double bound_mm = NAN;       // the one-frame bound on d at this truth (NaN: none)
};

// The filter's velocity on one segment's cruise (its frames from `cruise_settle_s` in).
struct TrackCruise {
  int segment = 0;
  int frames = 0;
  double truth_v_mm_per_s = NAN;
  double v_mean_mm_per_s = NAN, v_se_mean_mm_per_s = NAN;
  double z_mean = NAN;  // |v mean - truth| / se mean
  double z_last = NAN;  // the last cruising frame's |v - truth| / se
  bool within_3se = false;  // z_mean <= 3 and z_last <= 3
};

struct TrackSummary {
  std::string truth_source;  // "virtual rig trajectory (mid-exposure)" or "commanded profile"
  std::string bound_source;  // "Cramer-Rao bound of one frame (virtual rig physics)" or ...
  int frames = 0, estimated = 0, with_truth = 0, moving = 0;
  // Over the moving frames (truth velocity not 0) with an estimate:
  double error_rms_mm = NAN, error_mean_mm = NAN, error_max_mm = NAN;
  double bound_rms_mm = NAN;   // rms of the one-frame bound at the frames' truths
  double truth_sd_mm = 0.0;    // rms of the truth's own uncertainty
  double se_rms_mm = NAN;      // rms of the frames' reported standard errors
  double ratio_to_bound = NAN;  // error_rms / sqrt(bound_rms^2 + truth_sd^2)
  double goal_ratio = 1.5;
  // The filter's velocity error over the moving frames it took.
  int velocity_frames = 0;
  double velocity_error_rms_mm_per_s = NAN;
  std::vector<TrackCruise> cruises;
};

// The figures of `rows` against `truths` (one per row). Frames of a cruise count from
// `cruise_settle_s` after it began (the filter's memory of the acceleration).
TrackSummary SummarizeTrack(const std::vector<TrackFrameRow>& rows,
                            const std::vector<TrackTruth>& truths, double cruise_settle_s);

// summary.yaml of a track run: `kind: track`, the figures, and `counters` / `context` as given
// (name -> value, written in order). Throws RecordingError when it cannot be written.
struct TrackSummaryContext {
  std::vector<std::pair<std::string, std::string>> context;   // recipe, model, rig, ...
  std::vector<std::pair<std::string, std::int64_t>> counters;  // triggered, received, lost, ...
  bool cut = false;  // stopped before the profile's end (Ctrl-C, a failure)
};
std::string TrackSummaryYaml(const TrackSummary& summary, const TrackSummaryContext& context);
void WriteTrackSummary(const std::string& path, const TrackSummary& summary,
                       const TrackSummaryContext& context);

}  // namespace irdist
