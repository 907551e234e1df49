#include "app/live/measure_output.h"

#include <sys/ioctl.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <sstream>

#include "acquisition/recording_reader.h"
#include "app/processing/position.h"
#include "base/pi.h"
#include "base/utc_time.h"

namespace irdist {

std::string FixedText(double value, int decimals) {
  if (!std::isfinite(value)) return "-";
  char text[40];
  std::snprintf(text, sizeof(text), "%.*f", decimals, value);
  return text;
}

std::string JsonNumber(double value) {
  if (!std::isfinite(value)) return "null";
  char text[40];
  std::snprintf(text, sizeof(text), "%.10g", value);
  return text;
}

namespace {

const char* JsonBool(bool value) { return value ? "true" : "false"; }

// The bracket's absolute time keys (utc_time, host_monotonic_ns, camera_timestamp_ns), each with
// its leading comma.
std::string TimeJson(const MeasureSample& s) {
  std::string out = ",\"utc_time\":";
  out += s.utc_ns != 0 ? "\"" + FormatUtcIso8601(s.utc_ns) + "\"" : std::string("null");
  out += ",\"host_monotonic_ns\":" + std::to_string(s.host_monotonic_ns);
  out += ",\"camera_timestamp_ns\":";
  out += s.camera_timestamp_ns != 0 ? std::to_string(s.camera_timestamp_ns) : std::string("null");
  return out;
}

double Se(double value) { return value >= 0.0 ? value : std::nan(""); }

}  // namespace

namespace {

// The flags of estimate_flags.h that the sample's own fields do not carry: the scene's and the
// graded exposure note.
bool IsSceneFlag(const std::string& name) {
  for (const char* scene : {"defect_pixels", "other_blobs", "second_source", "occluded",
                            "t_meas_extrapolated"}) {
    if (name == scene) return true;
  }
  return false;
}

// "causes": every flag of the estimate with its figure and whether it makes it suspect.
std::string CausesJson(const MeasureSample& s) {
  std::string out = "[";
  if (!s.have_estimate) return out + "]";
  for (const EstimateFlag& f : s.estimate.flags) {
    const FlagSpec* spec = FindFlagSpec(f.name);
    out += (out.size() > 1 ? ",{" : "{") + std::string("\"name\":\"") + f.name +
           "\",\"figure\":\"" + f.figure + "\",\"suspect\":" +
           JsonBool(spec == nullptr || spec->suspect) + "}";
  }
  return out + "]";
}

}  // namespace

std::string QualityFlags(const MeasureSample& s) {
  std::string flags;
  const auto add = [&flags](bool on, const std::string& name) {
    if (on) flags += (flags.empty() ? "" : ",") + name;
  };
  add(!s.blob_found, "no_blob");
  add(s.saturated, "saturated");
  add(s.touches_border, "touches_border");
  add(s.clipped, "clipped");
  for (const EstimateFlag& f : s.estimate.flags) {  // the scene's flags and the graded notes
    add(s.have_estimate && IsSceneFlag(f.name), f.name + (f.figure.empty() ? "" : "(" + f.figure + ")"));
  }
  add(s.have_estimate && s.estimate.outside_range,
      "outside_range(" + JoinNames(s.estimate.outside, " ") + ")");
  add(s.health.flagged, std::string(s.health.refocused ? "refocused" : s.health.Label()) + "(" +
                            (s.health.sigma_change > 0.0 ? "+" : "") +
                            FixedText(100.0 * s.health.sigma_change, 0) + "%)");
  add(s.motion.moving, "moving(" + FixedText(s.motion.spread_mm, 1) + " mm)");
  add(!s.have_estimate || !s.estimate.ok, "no_estimate");
  return flags.empty() ? "ok" : flags;
}

namespace {

// "health": the figure behind the flag (null when not assessed).
std::string HealthJson(const HealthCheck& h) {
  if (!h.assessed) return "null";
  return std::string("{\"status\":\"") + h.Label() +
         "\",\"blur_var_px2\":" + JsonNumber(h.blur_var_px2) +
         ",\"calibrated_blur_var_px2\":" + JsonNumber(h.calibrated_px2) +
         ",\"sigma_change\":" + JsonNumber(h.sigma_change) + ",\"z\":" + JsonNumber(h.z) +
         ",\"figure\":\"" + (h.blob_fit ? "blob_fit" : "cumulants") +
         "\",\"refocused\":" + JsonBool(h.refocused) + "}";
}

// "motion": the figure behind the flag (null when not assessed).
std::string MotionJson(const MotionCheck& m) {
  if (!m.assessed) return "null";
  return "{\"spread_mm\":" + JsonNumber(m.spread_mm) + ",\"chi2\":" + JsonNumber(m.chi2) +
         ",\"chi2_limit\":" + JsonNumber(m.chi2_limit) +
         ",\"exposures\":" + std::to_string(m.exposures) + "}";
}

std::string NamesJson(const std::vector<std::string>& names) {
  std::string out = "[";
  for (const std::string& name : names) out += (out.size() > 1 ? ",\"" : "\"") + name + "\"";
  return out + "]";
}

}  // namespace

std::string MeasureJson(const MeasureSample& s) {
  const EstimateRow& e = s.estimate;
  const bool ok = s.have_estimate && e.ok;
  std::ostringstream out;
  out << "{\"schema\":\"irdist.measure/" << kMeasureJsonVersion << "\",\"mode\":\"" << s.mode
      << "\",\"bracket\":" << s.bracket
      << ",\"time_s\":" << JsonNumber(s.time_s) << TimeJson(s)
      << ",\"latency_ms\":" << JsonNumber(s.latency_ms) << ",\"ok\":" << JsonBool(ok)
      << ",\"d_mm\":" << JsonNumber(ok ? e.d_mm : NAN)
      << ",\"d_se_mm\":" << JsonNumber(ok ? Se(e.d_std_mm) : NAN)
      << ",\"theta_deg\":" << JsonNumber(ok ? e.theta_deg : NAN)
      << ",\"theta_se_deg\":" << JsonNumber(ok ? Se(e.theta_std_deg) : NAN)
      << ",\"blob_x_px\":" << JsonNumber(s.blob_found ? s.blob_x_px : NAN)
      << ",\"blob_y_px\":" << JsonNumber(s.blob_found ? s.blob_y_px : NAN) << ",\"flags\":{"
      << "\"no_blob\":" << JsonBool(!s.blob_found) << ",\"saturated\":" << JsonBool(s.saturated)
      << ",\"touches_border\":" << JsonBool(s.touches_border)
      << ",\"clipped\":" << JsonBool(s.clipped)
      << ",\"outside_range\":" << JsonBool(s.have_estimate && e.outside_range)
      << ",\"unhealthy\":" << JsonBool(s.health.flagged)
      << ",\"refocused\":" << JsonBool(s.health.refocused)
      << ",\"moving\":" << JsonBool(s.motion.moving)
      << ",\"second_source\":" << JsonBool(HasFlag(e.flags, "second_source"))
      << ",\"occluded\":" << JsonBool(HasFlag(e.flags, "occluded")) << "}"
      << ",\"trusted\":" << JsonBool(ok && e.Trusted()) << ",\"causes\":" << CausesJson(s)
      << ",\"outside\":" << NamesJson(s.have_estimate ? e.outside : std::vector<std::string>{})
      << ",\"health\":" << HealthJson(s.health) << ",\"motion\":" << MotionJson(s.motion)
      << ",\"position\":";
  if (ok && s.has_position) {
    out << "{\"x_mm\":" << JsonNumber(s.x_mm) << ",\"y_mm\":" << JsonNumber(s.y_mm)
        << ",\"z_mm\":" << JsonNumber(s.z_mm) << ",\"x_se_mm\":" << JsonNumber(s.x_se_mm)
        << ",\"y_se_mm\":" << JsonNumber(s.y_se_mm) << ",\"z_se_mm\":" << JsonNumber(s.z_se_mm)
        << "}";
  } else {
    out << "null";
  }
  out << "}";
  return out.str();
}

namespace {

// The live line's fields in display order, each with its rank: the lowest ranks are dropped
// first when the line does not fit the terminal (the distance and the flags stay).
struct LineField {
  std::string text;
  int rank;
};

std::vector<LineField> MeasureLineFields(const MeasureSample& s) {
  const EstimateRow& e = s.estimate;
  const bool ok = s.have_estimate && e.ok;
  std::vector<LineField> fields;
  fields.push_back({"#" + std::to_string(s.bracket), 5});
  fields.push_back({"t " + FixedText(s.time_s, 2) + " s", 1});
  fields.push_back({"d " + FixedText(ok ? e.d_mm : NAN, 1) + " +- " +
                        FixedText(ok ? Se(e.d_std_mm) : NAN, 1) + " mm", 7});
  fields.push_back({"theta " + FixedText(ok ? e.theta_deg : NAN, 2) + " +- " +
                        FixedText(ok ? Se(e.theta_std_deg) : NAN, 2) + " deg", 4});
  fields.push_back({"blob (" + FixedText(s.blob_found ? s.blob_x_px : NAN, 1) + ", " +
                        FixedText(s.blob_found ? s.blob_y_px : NAN, 1) + ") px", 2});
  if (ok && s.has_position) {
    fields.push_back({"xyz (" + FixedText(s.x_mm, 1) + ", " + FixedText(s.y_mm, 1) + ", " +
                          FixedText(s.z_mm, 1) + ") mm", 3});
  }
  fields.push_back({"[" + QualityFlags(s) + "]", 6});
  return fields;
}

std::string JoinFields(const std::vector<LineField>& fields) {
  std::string line;
  for (const LineField& f : fields) line += (line.empty() ? "" : "  ") + f.text;
  return line;
}

}  // namespace

std::string MeasureLine(const MeasureSample& s) { return JoinFields(MeasureLineFields(s)); }

std::string MeasureLine(const MeasureSample& s, std::size_t width_chars) {
  std::vector<LineField> fields = MeasureLineFields(s);
  // One column short of the width: a line that fills the last column wraps on some terminals.
  const std::size_t fit_chars = width_chars > 1 ? width_chars - 1 : 1;
  std::string line = JoinFields(fields);
  while (line.size() > fit_chars && fields.size() > 1) {
    const auto lowest = std::min_element(fields.begin(), fields.end(),
        [](const LineField& a, const LineField& b) { return a.rank < b.rank; });
    fields.erase(lowest);
    line = JoinFields(fields);
  }
  return line.substr(0, fit_chars);
}

std::size_t TerminalWidthChars(int fd) {
  winsize size{};
  if (isatty(fd) == 1 && ioctl(fd, TIOCGWINSZ, &size) == 0 && size.ws_col > 0) {
    return size.ws_col;
  }
  return 80;
}

void MeasureStats::Moments::Add(double value) {
  ++n;
  const double delta = value - mean;
  mean += delta / n;
  m2 += delta * (value - mean);
}

double MeasureStats::Moments::Sd() const { return n > 1 ? std::sqrt(m2 / (n - 1)) : NAN; }

void MeasureStats::Add(const MeasureSample& s) {
  ++count_;
  if (std::isfinite(s.latency_ms)) latency_.Add(s.latency_ms);
  health_assessed_ += s.health.assessed ? 1 : 0;
  unhealthy_ += s.health.flagged ? 1 : 0;
  motion_assessed_ += s.motion.assessed ? 1 : 0;
  moving_ += s.motion.moving ? 1 : 0;
  if (s.have_estimate && s.estimate.outside_range) {
    ++outside_;
    for (const std::string& name : s.estimate.outside) ++outside_by_range_[name];
  }
  if (s.have_estimate) {
    for (const EstimateFlag& f : s.estimate.flags) ++by_flag_[f.name];
  }
  suspect_ += s.have_estimate && s.estimate.Trusted() ? 0 : 1;
  if (!s.have_estimate || !s.estimate.ok) return;
  ++estimated_;
  d_.Add(s.estimate.d_mm);
  theta_.Add(s.estimate.theta_deg);
  if (!s.has_position) return;
  x_.Add(s.x_mm);
  y_.Add(s.y_mm);
  z_.Add(s.z_mm);
}

std::string MeasureStats::Report(double wall_s) const {
  std::ostringstream out;
  out << "Measured " << count_ << " brackets in " << FixedText(wall_s, 2) << " s ("
      << FixedText(wall_s > 0.0 ? count_ / wall_s : NAN, 2) << " brackets/s), " << estimated_
      << " with an estimate\n";
  const auto line = [&out](const char* name, const Moments& m, const char* unit, int decimals) {
    if (m.n == 0) return;
    out << "  " << name << ": mean " << FixedText(m.mean, decimals) << " " << unit << ", sd "
        << FixedText(m.Sd(), decimals) << " " << unit << "\n";
  };
  line("d", d_, "mm", 2);
  line("theta", theta_, "deg", 3);
  line("x", x_, "mm", 2);
  line("y", y_, "mm", 2);
  line("z", z_, "mm", 2);
  line("latency (last frame to estimate)", latency_, "ms", 3);
  out << "  health: " << unhealthy_ << " of " << health_assessed_
      << " assessed brackets unhealthy (blur off the calibration's)\n";
  out << "  motion: " << moving_ << " of " << motion_assessed_ << " assessed brackets moving\n";
  std::string ranges;
  for (const auto& [name, n] : outside_by_range_) {
    ranges += (ranges.empty() ? "" : ", ") + name + " " + std::to_string(n);
  }
  out << "  outside the calibrated ranges: " << outside_
      << (ranges.empty() ? "" : " (" + ranges + ")") << "\n";
  std::string flags;
  for (const auto& [name, n] : by_flag_) {
    const FlagSpec* spec = FindFlagSpec(name);
    flags += (flags.empty() ? "" : ", ") + name + " " + std::to_string(n) +
             (spec != nullptr && !spec->suspect ? " (note)" : "");
  }
  out << "  suspect: " << suspect_ << " of " << count_ << " brackets"
      << (flags.empty() ? "" : " (flags: " + flags + ")") << "\n";
  return out.str();
}

MeasureSample MeasureSampleOf(const RecordedBracket& bracket, const FeatureMap& features,
                              const BracketEstimateRows& rows, const CalibrationModel& model,
                              const CameraGeometry& geometry) {
  MeasureSample s;
  s.bracket = bracket.bracket_id;
  s.health = rows.health;
  s.motion = rows.motion;
  if (!rows.i0_free.empty()) {
    s.estimate = rows.i0_free.front();
    s.have_estimate = true;
    // theta from the calibrated ellipse correction (not solved): its calibration scatter, the sd
    // of a normal law whose mean |error| the fit recorded.
    const ThetaCorrection& tc = model.theta_correction;
    if (s.estimate.theta_std_deg < 0.0 && tc.fitted()) {
      s.estimate.theta_std_deg = std::sqrt(kPi / 2.0) * tc.summary.mean_relative_error;
    }
  }
  const Features& last = features.at(bracket.frames.back().index);
  s.blob_found = last.blob_found;
  s.blob_x_px = last.centroid_px.x + geometry.roi_offset_x;
  s.blob_y_px = last.centroid_px.y + geometry.roi_offset_y;
  for (const FrameRecord& row : bracket.frames) {
    const Features& f = features.at(row.index);
    s.blob_found = s.blob_found && f.blob_found;
    s.saturated = s.saturated || f.saturated_pixels > 0;
    s.touches_border = s.touches_border || f.touches_border;
    s.clipped = s.clipped || f.blob_clipped_by_roi;
  }
  s.has_position = s.have_estimate && std::isfinite(s.estimate.x_mm);
  s.x_mm = s.estimate.x_mm;
  s.y_mm = s.estimate.y_mm;
  s.z_mm = s.estimate.z_mm;
  s.x_se_mm = s.estimate.x_se_mm;
  s.y_se_mm = s.estimate.y_se_mm;
  s.z_se_mm = s.estimate.z_se_mm;
  return s;
}

}  // namespace irdist
