#include "app/processing/estimate_flags.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace irdist {

namespace {

std::string Fixed(double value, int decimals, const char* unit) {
  char text[48];
  std::snprintf(text, sizeof(text), "%.*f%s", decimals, value, unit);
  return text;
}


// `t_meas` within kExposureExtrapolation of the calibrated exposures: the note's figure (the
// farthest exposure, ms), or "" when some exposure lies beyond the tolerance.
std::string GradedExposure(const CalibratedRanges& ranges, const std::vector<double>& t_ms) {
  double farthest_ms = NAN, farthest_beyond = 0.0;
  for (double t : t_ms) {
    const double beyond = t > ranges.t_max_ms   ? t / ranges.t_max_ms - 1.0
                          : t < ranges.t_min_ms ? 1.0 - t / ranges.t_min_ms
                                                : 0.0;
    if (!(beyond <= kExposureExtrapolation)) return "";
    if (beyond > farthest_beyond) {
      farthest_beyond = beyond;
      farthest_ms = t;
    }
  }
  return std::isfinite(farthest_ms) ? Fixed(farthest_ms, 1, "ms") : "";
}

// The bracket's peak within kSignalExtrapolation of the calibrated peaks: the note's figure (the
// farthest, % beyond the nearest edge), or "" when beyond the tolerance.
std::string GradedSignal(const CalibratedRanges& ranges, const BracketFrameFlags& frames) {
  if (!(ranges.peak_max > 0.0 && frames.peak_max > 0.0)) return "";
  const double above = frames.peak_max / ranges.peak_max - 1.0;
  const double below = 1.0 - frames.peak_min / ranges.peak_min;
  const double beyond = std::max(above, below);
  if (!(beyond <= kSignalExtrapolation)) return "";
  return (above >= below ? "+" : "-") + Fixed(100.0 * beyond, 0, "%");
}

// Moves `name` from the row's outside list to the note `note` when `figure` grades it.
void Grade(const char* name, const char* note, const std::string& figure, EstimateRow* row) {
  auto& outside = row->outside;
  const auto it = std::find(outside.begin(), outside.end(), name);
  if (it == outside.end() || figure.empty()) return;
  outside.erase(it);
  row->flags.push_back({note, figure});
}

// The row's outside ranges as its flags: a graded t_meas or signal becomes a note and leaves the
// list.
void FlagRanges(const CalibratedRanges& ranges, const BracketFrameFlags& frames,
                const std::vector<double>& t_ms, EstimateRow* row) {
  if (ranges.t_max_ms > 0.0) {
    Grade("t_meas", "t_meas_extrapolated", GradedExposure(ranges, t_ms), row);
  }
  Grade("signal", "signal_extrapolated", GradedSignal(ranges, frames), row);
  const auto& outside = row->outside;
  row->outside_range = !outside.empty();
  if (row->outside_range) row->flags.push_back({"outside", JoinNames(outside, "+")});
}

}  // namespace

void SceneFigures::Add(const Features* f) {
  ++frames;
  if (f != nullptr) background_max = std::max(background_max, f->background);
  if (f == nullptr || !f->blob_found) {
    ++no_blob;
    return;
  }
  touches_border = touches_border || f->touches_border;
  clipped = clipped || f->blob_clipped_by_roi;
  saturated_frames += f->saturated_pixels > 0 ? 1 : 0;
  saturated_px = std::max(saturated_px, f->saturated_pixels);
  peak_min = peak_max > 0.0 ? std::min(peak_min, f->peak) : f->peak;
  peak_max = std::max(peak_max, f->peak);
  const SceneReport& s = f->scene;
  defect_pixels = std::max(defect_pixels, s.defect_pixels);
  other_blobs = std::max(other_blobs, s.other_blobs);
  if (s.second_source) {
    ++second_source;
    if (std::isfinite(s.second_source_gap_px) &&
        !(second_source_gap_px <= s.second_source_gap_px)) {
      second_source_gap_px = s.second_source_gap_px;
    }
  }
  if (s.occluded) {
    ++occluded;
    occluded_edge_fraction = std::max(occluded_edge_fraction, s.occluded_edge_fraction);
  }
}

double DisagreementTolerance(const CalibrationModel& model) {
  const double fit_error = model.geometric.fitted()
                               ? std::max(model.geometric.summary.mean_relative_error, 0.0)
                               : 0.0;
  return std::max(0.005, 10.0 * fit_error);
}

void FlagDisagreement(const EstimateRow& size, double tolerance, EstimateRow* row) {
  if (!row->ok || !size.ok || !(size.d_mm > 0.0)) return;
  const double departure = row->d_mm / size.d_mm - 1.0;
  if (std::abs(departure) <= tolerance) return;
  row->flags.push_back({"disagrees", (departure > 0.0 ? "+" : "") +
                                         Fixed(100.0 * departure, 1, "%")});
}

std::string PercentFigure(double fraction) {
  return (fraction > 0.0 ? "+" : "") + Fixed(100.0 * fraction, 0, "%");
}

BracketFrameFlags FrameFlags(const std::vector<const Features*>& frames) {
  SceneFigures w;
  for (const Features* f : frames) w.Add(f);
  BracketFrameFlags out;
  out.peak_min = w.peak_min;
  out.peak_max = w.peak_max;
  std::vector<EstimateFlag>& flags = out.flags;
  if (w.defect_pixels > 0) flags.push_back({"defect_pixels", std::to_string(w.defect_pixels)});
  if (w.other_blobs > 0 && w.second_source == 0) {
    flags.push_back({"other_blobs", std::to_string(w.other_blobs)});
  }
  if (w.no_blob > 0) flags.push_back({"no_blob", ""});
  if (w.saturated_px > 0) flags.push_back({"saturated", std::to_string(w.saturated_px)});
  if (w.touches_border) flags.push_back({"touches_border", ""});
  if (w.clipped) flags.push_back({"clipped", ""});
  if (w.second_source > 0) {
    flags.push_back({"second_source", std::isfinite(w.second_source_gap_px)
                                          ? Fixed(w.second_source_gap_px, 1, "px")
                                          : ""});
  }
  if (w.occluded > 0) {
    flags.push_back({"occluded", Fixed(100.0 * w.occluded_edge_fraction, 0, "%")});
  }
  return out;
}

void FlagRow(const BracketFrameFlags& frames, const CalibratedRanges& ranges,
             const std::vector<double>& t_ms, const HealthCheck* health, EstimateRow* row) {
  const std::vector<EstimateFlag>& frame_flags = frames.flags;
  row->flags = frame_flags;
  // A second source or an occluder changes the blob's spread and the per-exposure distances: its
  // own flag names the cause, never motion or focus.
  const bool scene_cause =
      HasFlag(frame_flags, "second_source") || HasFlag(frame_flags, "occluded");
  if (!scene_cause && row->motion == "moving") {
    row->flags.push_back({"moving", Fixed(row->spread_mm, 1, "mm")});
  }
  if (!scene_cause && health != nullptr && health->assessed && health->flagged) {
    // Measured through with the bracket's own blur: a note; else the blur makes it suspect.
    row->flags.push_back({health->refocused ? "refocused" : health->Label(),
                          PercentFigure(health->sigma_change)});
  }
  FlagRanges(ranges, frames, t_ms, row);
  if (!row->ok) row->flags.push_back({"no_estimate", ""});
}

}  // namespace irdist
