#include "app/processing/track_summary.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cstdio>

#include "acquisition/recording_types.h"
#include "base/check.h"
#include "base/safe_file.h"
#include "base/utc_time.h"

namespace irdist {

namespace {

// %.10g, or an empty cell when not finite.
std::string Cell(double value) {
  if (!std::isfinite(value)) return "";
  char text[64];
  std::snprintf(text, sizeof(text), "%.10g", value);
  return text;
}

// Root of the mean of `sum2` over `n` (NaN when n is 0).
double Rms(double sum2, int n) { return n > 0 ? std::sqrt(sum2 / n) : NAN; }

// The filter's velocity on each segment's cruise.
std::vector<TrackCruise> Cruises(const std::vector<TrackFrameRow>& rows,
                                 const std::vector<TrackTruth>& truths, double settle_s) {
  std::vector<TrackCruise> cruises;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const TrackFrameRow& r = rows[i];
    const TrackTruth& t = truths[i];
    if (!t.known || !(t.cruise_s >= settle_s) || !r.filtered || !(r.v_se_mm_per_s > 0.0)) continue;
    if (cruises.empty() || cruises.back().segment != r.segment) {
      cruises.push_back({});
      cruises.back().segment = r.segment;
      cruises.back().truth_v_mm_per_s = t.v_mm_per_s;
      cruises.back().v_mean_mm_per_s = cruises.back().v_se_mean_mm_per_s = 0.0;
    }
    TrackCruise& c = cruises.back();
    ++c.frames;
    c.v_mean_mm_per_s += r.v_mm_per_s;
    c.v_se_mean_mm_per_s += r.v_se_mm_per_s;
    c.z_last = std::fabs(r.v_mm_per_s - t.v_mm_per_s) / r.v_se_mm_per_s;
  }
  for (TrackCruise& c : cruises) {
    c.v_mean_mm_per_s /= c.frames;
    c.v_se_mean_mm_per_s /= c.frames;
    c.z_mean = std::fabs(c.v_mean_mm_per_s - c.truth_v_mm_per_s) / c.v_se_mean_mm_per_s;
    c.within_3se = c.z_mean <= 3.0 && c.z_last <= 3.0;
  }
  return cruises;
}

void EmitNumber(YAML::Emitter& out, const char* key, double value) {
  out << YAML::Key << key << YAML::Value;
  if (std::isfinite(value)) {
    out << value;
  } else {
    out << YAML::Null;
  }
}

void EmitCruises(YAML::Emitter& out, const std::vector<TrackCruise>& cruises) {
  out << YAML::Key << "velocity_on_cruise" << YAML::Value << YAML::BeginSeq;
  for (const TrackCruise& c : cruises) {
    out << YAML::BeginMap;
    out << YAML::Key << "segment" << YAML::Value << c.segment;
    out << YAML::Key << "frames" << YAML::Value << c.frames;
    EmitNumber(out, "truth_v_mm_per_s", c.truth_v_mm_per_s);
    EmitNumber(out, "v_mean_mm_per_s", c.v_mean_mm_per_s);
    EmitNumber(out, "v_se_mean_mm_per_s", c.v_se_mean_mm_per_s);
    EmitNumber(out, "z_mean", c.z_mean);
    EmitNumber(out, "z_last", c.z_last);
    out << YAML::Key << "within_3se" << YAML::Value << c.within_3se;
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;
}

}  // namespace

std::string TrackCsvHeader() {
  return "frame,camera_frame_id,camera_timestamp_ns,utc_time,exposure_ms,segment,ok,d_mm,d_se_mm,"
         "theta_deg,filtered,track_d_mm,track_d_se_mm,v_mm_per_s,v_se_mm_per_s,flags";
}

std::string TrackCsvRow(const TrackFrameRow& r) {
  std::string flags = r.flags;
  std::replace(flags.begin(), flags.end(), ',', ' ');  // one cell, never a column more
  return std::to_string(r.frame) + ',' + std::to_string(r.camera_frame_id) + ',' +
         (r.camera_timestamp_ns ? std::to_string(r.camera_timestamp_ns) : "") + ',' +
         (r.utc_ns > 0 ? FormatUtcIso8601(r.utc_ns) : "") + ',' + Cell(r.exposure_ms) + ',' +
         std::to_string(r.segment) + ',' + (r.ok ? "1" : "0") + ',' + Cell(r.d_mm) + ',' +
         Cell(r.d_se_mm) + ',' + Cell(r.theta_deg) + ',' + (r.filtered ? "1" : "0") + ',' +
         Cell(r.track_d_mm) + ',' + Cell(r.track_d_se_mm) + ',' + Cell(r.v_mm_per_s) + ',' +
         Cell(r.v_se_mm_per_s) + ',' + flags;
}

TrackSummary SummarizeTrack(const std::vector<TrackFrameRow>& rows,
                            const std::vector<TrackTruth>& truths, double cruise_settle_s) {
  IRDIST_CHECK(rows.size() == truths.size(), "rows ", rows.size(), " truths ", truths.size());
  TrackSummary s;
  double e2 = 0.0, e_sum = 0.0, b2 = 0.0, t2 = 0.0, se2 = 0.0, v2 = 0.0;
  int bound_n = 0;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const TrackFrameRow& r = rows[i];
    const TrackTruth& t = truths[i];
    ++s.frames;
    s.estimated += r.ok ? 1 : 0;
    if (!t.known) continue;
    ++s.with_truth;
    if (std::fabs(t.v_mm_per_s) < 1e-9) continue;  // the profile's moves only
    if (r.filtered && std::isfinite(r.v_mm_per_s)) {
      ++s.velocity_frames;
      v2 += (r.v_mm_per_s - t.v_mm_per_s) * (r.v_mm_per_s - t.v_mm_per_s);
    }
    if (!r.ok) continue;
    ++s.moving;
    const double e = r.d_mm - t.d_mm;
    e2 += e * e;
    e_sum += e;
    s.error_max_mm = std::isfinite(s.error_max_mm) ? std::max(s.error_max_mm, std::fabs(e))
                                                   : std::fabs(e);
    t2 += t.sd_mm * t.sd_mm;
    se2 += r.d_se_mm * r.d_se_mm;
    if (std::isfinite(t.bound_mm)) {
      b2 += t.bound_mm * t.bound_mm;
      ++bound_n;
    }
  }
  s.error_rms_mm = Rms(e2, s.moving);
  s.error_mean_mm = s.moving > 0 ? e_sum / s.moving : NAN;
  s.truth_sd_mm = s.moving > 0 ? Rms(t2, s.moving) : 0.0;
  s.se_rms_mm = Rms(se2, s.moving);
  s.bound_rms_mm = bound_n == s.moving ? Rms(b2, bound_n) : NAN;  // every frame, or none
  s.ratio_to_bound =
      s.error_rms_mm / std::sqrt(s.bound_rms_mm * s.bound_rms_mm + s.truth_sd_mm * s.truth_sd_mm);
  s.velocity_error_rms_mm_per_s = Rms(v2, s.velocity_frames);
  s.cruises = Cruises(rows, truths, cruise_settle_s);
  return s;
}

std::string TrackSummaryYaml(const TrackSummary& s, const TrackSummaryContext& c) {
  YAML::Emitter out;
  out.SetDoublePrecision(6);
  out << YAML::BeginMap << YAML::Key << "kind" << YAML::Value << "track";
  for (const auto& [key, value] : c.context) out << YAML::Key << key << YAML::Value << value;
  out << YAML::Key << "cut" << YAML::Value << c.cut;
  out << YAML::Key << "truth" << YAML::Value << s.truth_source;
  out << YAML::Key << "bound" << YAML::Value << s.bound_source;
  out << YAML::Key << "frames" << YAML::Value << YAML::BeginMap;
  for (const auto& [key, value] : c.counters) out << YAML::Key << key << YAML::Value << value;
  out << YAML::Key << "rows" << YAML::Value << s.frames << YAML::Key << "estimated"
      << YAML::Value << s.estimated << YAML::Key << "with_truth" << YAML::Value << s.with_truth
      << YAML::Key << "moving" << YAML::Value << s.moving << YAML::EndMap;
  out << YAML::Key << "distance_error_moving" << YAML::Value << YAML::BeginMap;
  EmitNumber(out, "rms_mm", s.error_rms_mm);
  EmitNumber(out, "mean_mm", s.error_mean_mm);
  EmitNumber(out, "max_abs_mm", s.error_max_mm);
  EmitNumber(out, "one_frame_bound_rms_mm", s.bound_rms_mm);
  EmitNumber(out, "truth_sd_mm", s.truth_sd_mm);
  EmitNumber(out, "se_rms_mm", s.se_rms_mm);
  EmitNumber(out, "rms_over_bound", s.ratio_to_bound);
  EmitNumber(out, "goal_rms_over_bound", s.goal_ratio);
  out << YAML::Key << "within_goal" << YAML::Value << (s.ratio_to_bound <= s.goal_ratio);
  out << YAML::EndMap;
  out << YAML::Key << "velocity" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "frames" << YAML::Value << s.velocity_frames;
  EmitNumber(out, "error_rms_mm_per_s", s.velocity_error_rms_mm_per_s);
  EmitCruises(out, s.cruises);
  out << YAML::EndMap << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

void WriteTrackSummary(const std::string& path, const TrackSummary& summary,
                       const TrackSummaryContext& context) {
  std::string why;
  if (!WriteFileAtomically(path, TrackSummaryYaml(summary, context), 0644, &why)) {
    throw RecordingError(path + ": " + why + "; free space or check the folder is writable.");
  }
}

}  // namespace irdist
