#include "app/live/track_output.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace irdist {

namespace {

constexpr double kLatencyBinMs = 0.01;

const char* JsonBool(bool value) { return value ? "true" : "false"; }

std::string CountersJson(const TrackCounters& c) {
  return "{\"triggered\":" + std::to_string(c.triggered) +
         ",\"received\":" + std::to_string(c.received) +
         ",\"estimated\":" + std::to_string(c.estimated) +
         ",\"skipped\":" + std::to_string(c.skipped) + ",\"lost\":" + std::to_string(c.lost) +
         ",\"wrong_exposure\":" + std::to_string(c.wrong_exposure) +
         ",\"drained\":" + std::to_string(c.drained) + "}";
}

// "track": the filter's state after the frame (null when it did not see the frame).
std::string FilterJson(const TrackSample& s) {
  if (!s.filtered || s.filter.position_mm.empty()) return "null";
  const TrackState& f = s.filter;
  return "{\"d_mm\":" + JsonNumber(f.position_mm[0]) +
         ",\"d_se_mm\":" + JsonNumber(f.position_sd_mm[0]) +
         ",\"v_mm_per_s\":" + JsonNumber(f.velocity_mm_per_s[0]) +
         ",\"v_se_mm_per_s\":" + JsonNumber(f.velocity_sd_mm_per_s[0]) +
         ",\"used\":" + JsonBool(f.used) + ",\"started\":" + JsonBool(f.started) +
         ",\"chi2\":" + JsonNumber(f.chi2) + ",\"frames\":" + std::to_string(f.frames) +
         ",\"time_s\":" + JsonNumber(f.time_s) + "}";
}

std::string CheckJson(const TrackCheck& c) {
  if (!c.assessed) return "null";
  return "{\"track_d_mm\":" + JsonNumber(c.track_d_mm) +
         ",\"track_se_mm\":" + JsonNumber(c.track_se_mm) + ",\"z\":" + JsonNumber(c.z) +
         ",\"z_limit\":" + JsonNumber(c.z_limit) + ",\"agree\":" + JsonBool(c.agree) + "}";
}

}  // namespace

std::string TrackJson(const TrackSample& s) {
  std::string json = MeasureJson(s.estimate);
  json.pop_back();  // the closing brace: the track's keys follow measure's
  json += ",\"acquisition\":\"" + s.acquisition + "\",\"frame\":";
  json += s.frame >= 0 ? std::to_string(s.frame) : std::string("null");
  json += ",\"camera_frame_id\":";
  json += s.frame >= 0 ? std::to_string(s.camera_frame_id) : std::string("null");
  json += ",\"exposure_ms\":" + JsonNumber(s.exposure_ms) + ",\"cpu_ms\":" + JsonNumber(s.cpu_ms) +
          ",\"track\":" + FilterJson(s) + ",\"check\":" + CheckJson(s.check) +
          ",\"counters\":" + CountersJson(s.counters) + "}";
  return json;
}

std::string TrackLine(const TrackSample& s) {
  std::string line = std::string(s.estimate.mode) + " " + MeasureLine(s.estimate);
  if (s.filtered && !s.filter.position_mm.empty()) {
    line += "  track " + FixedText(s.filter.position_mm[0], 1) + " +- " +
            FixedText(s.filter.position_sd_mm[0], 1) + " mm, v " +
            FixedText(s.filter.velocity_mm_per_s[0], 1) + " +- " +
            FixedText(s.filter.velocity_sd_mm_per_s[0], 1) + " mm/s";
  }
  if (s.check.assessed) {
    line += std::string("  check ") + (s.check.agree ? "agrees" : "DISAGREES") + " (z " +
            FixedText(s.check.z, 1) + ")";
  }
  const TrackCounters& c = s.counters;
  if (c.skipped + c.lost + c.wrong_exposure > 0) {
    line += "  [skipped " + std::to_string(c.skipped) + ", lost " + std::to_string(c.lost) +
            (c.wrong_exposure > 0 ? ", wrong exposure " + std::to_string(c.wrong_exposure) : "") +
            "]";
  }
  return line;
}

TrackCheck CheckAgainstTrack(const TrackState& last, bool track_started, double bracket_time_s,
                             const MeasureSample& bracket) {
  TrackCheck check;
  const double bracket_se = bracket.estimate.d_std_mm;
  if (!track_started || last.position_mm.empty() || !bracket.have_estimate ||
      !bracket.estimate.ok || !(bracket_se > 0.0)) {
    return check;
  }
  const double dt_s = std::max(0.0, bracket_time_s - last.time_s);
  check.track_d_mm = last.position_mm[0] + last.velocity_mm_per_s[0] * dt_s;
  const double v_part = last.velocity_sd_mm_per_s[0] * dt_s;
  check.track_se_mm = std::sqrt(last.position_sd_mm[0] * last.position_sd_mm[0] + v_part * v_part);
  check.z = (bracket.estimate.d_mm - check.track_d_mm) /
            std::sqrt(bracket_se * bracket_se + check.track_se_mm * check.track_se_mm);
  check.assessed = std::isfinite(check.z);
  check.agree = !check.assessed || std::abs(check.z) <= check.z_limit;
  return check;
}

void TrackStats::Add(const TrackSample& s) {
  ++lines_;
  if (s.frame < 0) {
    ++checks_;
    disagree_ += s.check.assessed && !s.check.agree ? 1 : 0;
    return;
  }
  ++frames_;
  const double latency_ms = s.estimate.latency_ms;
  if (std::isfinite(latency_ms) && latency_ms >= 0.0) {
    const auto bin = std::min<std::size_t>(static_cast<std::size_t>(latency_ms / kLatencyBinMs),
                                           latency_bins_.size() - 1);
    ++latency_bins_[bin];
    latency_max_ms_ = std::max(latency_max_ms_, latency_ms);
  }
  const EstimateRow& e = s.estimate.estimate;
  suspect_ += s.estimate.have_estimate && e.Trusted() ? 0 : 1;
  if (!s.estimate.have_estimate || !e.ok) return;
  ++estimated_;
  d_sum_ += e.d_mm;
  d_sum2_ += e.d_mm * e.d_mm;
  if (e.d_std_mm > 0.0) se_sum2_ += e.d_std_mm * e.d_std_mm;
}

double TrackStats::LatencyQuantileMs(double q) const {
  std::int64_t total = 0;
  for (std::int64_t n : latency_bins_) total += n;
  if (total == 0) return NAN;
  const auto rank = static_cast<std::int64_t>(std::ceil(q * static_cast<double>(total)));
  std::int64_t seen = 0;
  for (std::size_t i = 0; i < latency_bins_.size(); ++i) {
    seen += latency_bins_[i];
    if (seen >= std::max<std::int64_t>(rank, 1))
      return (static_cast<double>(i) + 0.5) * kLatencyBinMs;
  }
  return latency_max_ms_;
}

std::string TrackStats::Report(double wall_s, const TrackCounters& c) const {
  std::ostringstream out;
  const double camera_fps = wall_s > 0.0 ? static_cast<double>(c.received + c.lost) / wall_s : NAN;
  const double estimate_fps = wall_s > 0.0 ? frames_ / wall_s : NAN;
  out << "Tracked " << frames_ << " frames in " << FixedText(wall_s, 2) << " s ("
      << FixedText(estimate_fps, 2) << " estimates/s; the camera delivered "
      << FixedText(camera_fps, 2) << " frames/s: ratio " << FixedText(estimate_fps / camera_fps, 3)
      << "), " << estimated_ << " with an estimate\n";
  out << "  frames: " << c.triggered << " triggered, " << c.received << " received, " << c.estimated
      << " estimated, " << c.skipped << " skipped (the estimator behind), " << c.lost << " lost, "
      << c.wrong_exposure << " at another exposure, " << c.drained
      << " drained as the grabbing stopped\n";
  out << "  latency (frame arrival to estimate): median " << FixedText(LatencyQuantileMs(0.5), 2)
      << " ms, p95 " << FixedText(LatencyQuantileMs(0.95), 2) << " ms, max "
      << FixedText(latency_max_ms_, 2) << " ms\n";
  if (estimated_ > 1) {
    const double mean = d_sum_ / estimated_;
    const double sd =
        std::sqrt(std::max(0.0, (d_sum2_ - estimated_ * mean * mean) / (estimated_ - 1)));
    out << "  d: mean " << FixedText(mean, 2) << " mm, sd " << FixedText(sd, 2)
        << " mm, rms reported se " << FixedText(std::sqrt(se_sum2_ / estimated_), 2) << " mm\n";
  }
  out << "  suspect: " << suspect_ << " of " << frames_ << " frames\n";
  if (checks_ > 0) {
    out << "  bracket checks: " << checks_ << ", " << disagree_ << " disagreeing with the track\n";
  }
  return out.str();
}

}  // namespace irdist
