#include "app/reports/report.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <optional>
#include <sstream>

#include "acquisition/recording_reader.h"
#include "app/reports/calibration_plots.h"
#include "base/process.h"
#include "base/safe_file.h"
#include "base/version.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;

std::string HtmlEscape(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '&':
        out += "&amp;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

// What to do when a report file cannot be written: the disk is the usual cause.
std::string WriteFix(const fs::path& path) {
  return "; free disk space (df -h " + path.parent_path().string() +
         ") or fix the folder's permissions";
}

// Whole or not at all (temporary file, sync, rename): a full disk never leaves a cut file.
void WriteFile(const fs::path& path, const std::string& text) {
  std::string why;
  if (!WriteFileAtomically(path.string(), text, 0644, &why)) {
    throw ReportError(path.string() + ": " + why + WriteFix(path));
  }
}

std::string ReadFile(const fs::path& path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string NowUtc() {
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm tm{};
  gmtime_r(&now, &tm);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return text;
}

std::string ErrorFiguresText(const ErrorFigures& f) {
  std::ostringstream s;
  s << f.count << " estimates" << (f.failed ? " (" + std::to_string(f.failed) + " failed)" : "")
    << "; |relative distance error| median " << FixedDigits(f.distance_rel_error_pct_median, 2)
    << " %, p95 " << FixedDigits(f.distance_rel_error_pct_p95, 2) << " %, max "
    << FixedDigits(f.distance_rel_error_pct_max, 2) << " %";
  return s.str();
}

// "converged, 72 samples, mean |error| 0.095 %" or "72 samples, degenerate (...)".
std::string FitText(const FittedModel& m) {
  std::ostringstream s;
  const std::string reason = UnreliableFitReason(m);
  if (reason.empty()) {
    s << ToString(m.summary.termination) << ", " << m.summary.samples << " samples, mean |error| "
      << FixedDigits(100.0 * m.summary.mean_relative_error, 3) << " %";
  } else {
    s << m.summary.samples << " samples, " << reason;
  }
  return s.str();
}

// The plot's script with terminal, output and data file set.
std::string GnuplotScript(const Plot& plot) {
  std::string body = plot.script;
  ReplaceAll(&body, "__DATA__", plot.name + ".dat");
  std::ostringstream gp;
  gp << "set terminal svg size " << plot.width_px << "," << plot.height_px
     << " dynamic enhanced font 'sans,11'\nset output '" << plot.name << ".svg'\n"
     << body;
  return gp.str();
}

// Runs gnuplot on <dir>/<name>.gp in <dir> (no shell: an argument vector), stderr to <name>.log.
// Returns "" when the SVG was drawn, else what went wrong.
std::string RunGnuplot(const fs::path& dir, const std::string& name) {
  ProcessSpec spec;
  spec.argv = {"gnuplot", name + ".gp"};
  spec.working_dir = dir.string();
  spec.stderr_path = (dir / (name + ".log")).string();
  try {
    const ProcessResult result = RunProgram(spec);
    if (!result.exited) return "gnuplot was killed by signal " + std::to_string(result.signal);
    if (result.exit_code != 0) {
      return "gnuplot exited with status " + std::to_string(result.exit_code);
    }
  } catch (const ProcessError& e) {
    return e.what();
  }
  return fs::exists(dir / (name + ".svg")) ? "" : "gnuplot wrote no " + name + ".svg";
}

std::string HeaderHtml(const std::string& title, const ReportFields& fields) {
  std::ostringstream html;
  html << "<h1>" << HtmlEscape(title) << "</h1>\n<table class='header'>\n";
  for (const auto& [label, value] : fields) {
    html << "<tr><th>" << HtmlEscape(label) << "</th><td>" << HtmlEscape(value) << "</td></tr>\n";
  }
  html << "</table>\n";
  return html.str();
}

std::string FigureHtml(const fs::path& dir, const Plot& plot, bool have_gnuplot) {
  WriteFile(dir / (plot.name + ".dat"), plot.data);
  WriteFile(dir / (plot.name + ".gp"), GnuplotScript(plot));
  std::ostringstream html;
  html << "<figure id='" << plot.name << "'><h2>" << HtmlEscape(plot.title) << "</h2>\n";
  const std::string problem = have_gnuplot ? RunGnuplot(dir, plot.name) : "gnuplot not found";
  if (problem.empty()) {
    const fs::path svg_path = dir / (plot.name + ".svg");
    const std::string svg = ReadFile(svg_path);
    // gnuplot exits 0 even when its output was cut short (a full disk): a cut SVG has no end tag.
    if (svg.find("</svg>") == std::string::npos) {
      throw ReportError(svg_path.string() + ": gnuplot's plot is cut short (no </svg>; the disk "
                        "is full?)" + WriteFix(svg_path));
    }
    const size_t start = svg.find("<svg");
    html << (start == std::string::npos ? svg : svg.substr(start)) << "\n";
  } else {
    html << "<p class='missing'>(not drawn: " << HtmlEscape(problem) << "; see " << plot.name
         << ".gp, " << plot.name << ".dat and " << plot.name << ".log)</p>\n";
  }
  html << "<figcaption>" << HtmlEscape(plot.caption) << "</figcaption></figure>\n";
  return html.str();
}

}  // namespace

ReportFields RecordingReportFields(const std::string& recording_dir) {
  ReportFields fields;
  if (recording_dir.empty()) return fields;
  try {
    const RecordingReader reader(recording_dir);
    const RecordingHeader& h = reader.header();
    fields.push_back({"recipe", h.recipe_path.empty() ? "(in recording.yaml)" : h.recipe_path});
    fields.push_back({"rig", h.rig_path.empty() ? "(in recording.yaml)" : h.rig_path});
    fields.push_back({"camera", h.camera.model + " serial " + h.camera.serial + ", " +
                                    h.pixel_format + ", " + std::to_string(h.bit_depth) + " bit"});
    fields.push_back({"recording", recording_dir + " (" + CompletionName(h.completion) + ", " +
                                       std::to_string(reader.rows().size()) + " frames)"});
    fields.push_back({"recorded", h.start_time + " by " + h.software_version});
  } catch (const Error& e) {
    fields.push_back({"recording", recording_dir + " (header not readable: " + e.what() + ")"});
  }
  return fields;
}

ReportFields CalibrationReportFields(const std::string& recording_dir,
                                     const std::string& model_path, const CalibrationModel& model) {
  ReportFields fields = RecordingReportFields(recording_dir);
  fields.push_back({"model", model_path});
  for (const FittedModel& m : model.models) {
    fields.push_back({std::string("fit ") + ToString(m.kind), FitText(m)});
  }
  if (model.geometric.fitted()) {
    fields.push_back(
        {"fit geometric",
         ToString(model.geometric.summary.termination) + std::string(", mean |error| ") +
             FixedDigits(100.0 * model.geometric.summary.mean_relative_error, 3) + " %"});
  }
  fields.push_back({"calibrated range", FixedDigits(model.ranges.d_min_mm, 0) + " - " +
                                            FixedDigits(model.ranges.d_max_mm, 0) + " mm, " +
                                            FixedDigits(model.ranges.theta_min_deg, 0) + " - " +
                                            FixedDigits(model.ranges.theta_max_deg, 0) + " deg"});
  const CalibrationFitness& f = model.fitness;
  if (f.assessed) {
    fields.push_back({"fitness", std::string(f.passed ? "passed" : "FAILED") +
                                     ", reduced chi-square " + FixedDigits(f.reduced_chi2, 2) +
                                     " (limit " + FixedDigits(f.limit, 2) + ", " +
                                     std::to_string(f.dof) + " dof), " +
                                     std::to_string(f.poses_over) + " of " +
                                     std::to_string(f.poses) + " poses over"});
  }
  return fields;
}

namespace {

// The Cramer-Rao bound beside a method's figures, in one line of the header.
std::string CrbFiguresText(const CrbFigures& c) {
  if (!c.available) return c.source;
  std::ostringstream out;
  out << std::fixed << std::setprecision(2) << "distance sd bound " << c.distance_sd_bound_mm_min
      << "-" << c.distance_sd_bound_mm_max << " mm";
  if (std::isfinite(c.distance_error_over_bound_rms)) {
    out << ", error/bound rms " << c.distance_error_over_bound_rms;
  }
  if (c.theta_ge15_count > 0) {
    out << std::setprecision(3) << "; theta (>= 15 deg) sd bound " << c.theta_ge15_sd_bound_deg_min
        << "-" << c.theta_ge15_sd_bound_deg_max << " deg, error rms "
        << c.theta_ge15_error_rms_deg << " deg = " << std::setprecision(2)
        << c.theta_ge15_error_over_bound_rms << "x bound; max at the bound (median of runs) "
        << std::setprecision(3) << c.theta_ge15_max_at_bound_deg_median << " deg";
  }
  if (c.dispersion_ratio_max) {
    out << std::setprecision(2) << "; dispersion / bound max " << *c.dispersion_ratio_max;
    if (c.theta_dispersion_ratio_max) out << " (theta " << *c.theta_dispersion_ratio_max << ")";
    for (const CrbPoseRatio& p : c.dispersion) {
      out << std::setprecision(0) << "; " << p.d_mm << " mm " << p.theta_deg << " deg "
          << p.bias_ma << " mA: " << std::setprecision(2) << p.distance_sd_mm << " / "
          << p.distance_sd_bound_mm << " mm";
    }
  }
  return out.str();
}

// A method's flags by cause, in one line of the header: the suspect rows, each flag's count
// (notes marked) and the trusted rows no flag caught.
std::string FlagsText(const MethodSummary& m) {
  std::ostringstream out;
  out << m.suspect << " of " << (m.all.count + m.all.failed) << " suspect";
  for (const auto& [name, count] : m.flags) {
    const FlagSpec* spec = FindFlagSpec(name);
    out << "; " << name << " " << count << (spec != nullptr && !spec->suspect ? " (note)" : "");
  }
  out << "; silently wrong " << m.silently_wrong;
  return out.str();
}

}  // namespace

ReportFields ValidationReportFields(const std::map<std::string, std::string>& context,
                                    const ValidationSummary& summary,
                                    const std::map<std::string, CrbFigures>& crb) {
  ReportFields fields;
  const auto recording = context.find("recording");
  if (recording != context.end()) fields = RecordingReportFields(recording->second);
  for (const auto& [key, value] : context) {  // the context wins over the recording's copy
    const std::string& name = key;  // a structured binding is not captured before C++20
    auto same =
        std::find_if(fields.begin(), fields.end(), [&](const auto& f) { return f.first == name; });
    if (same == fields.end()) {
      fields.push_back({key, value});
    } else if (!value.empty()) {
      same->second = value;
    }
  }
  for (const MethodSummary& m : summary.methods) {
    fields.push_back({"method " + m.method, ErrorFiguresText(m.all)});
  }
  for (const MethodSummary& m : summary.methods) {
    fields.push_back({"flags " + m.method, FlagsText(m)});
  }
  for (const MethodSummary& m : summary.methods) {
    const auto it = crb.find(m.method);
    if (it != crb.end()) fields.push_back({"CRB " + m.method, CrbFiguresText(it->second)});
  }
  return fields;
}

std::string WriteReport(const std::string& dir, const std::string& title,
                        const ReportFields& fields, const std::string& summary_text,
                        const std::vector<Plot>& plots) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw ReportError(dir + ": cannot create the report folder: " + ec.message());
  const bool have_gnuplot = !FindProgram("gnuplot").empty();
  ReportFields header = fields;
  header.push_back({"report written", NowUtc() + " by " + std::string(kSoftwareVersion)});
  std::ostringstream html;
  html << "<!DOCTYPE html>\n<html><head><meta charset='utf-8'><title>" << HtmlEscape(title)
       << "</title>\n<style>body{font-family:sans-serif;max-width:980px;margin:2em auto;}"
          "figure{margin:2em 0;}figcaption{color:#333;font-size:0.95em;}"
          "table.header{border-collapse:collapse;font-size:0.9em;}"
          "table.header th{text-align:left;padding:2px 12px 2px 0;vertical-align:top;}"
          "table.header td{padding:2px 0;}p.missing{color:#a00;}"
          "pre{background:#f4f4f4;padding:1em;white-space:pre-wrap;}</style></head><body>\n"
       << HeaderHtml(title, header) << "<pre>" << HtmlEscape(summary_text) << "</pre>\n";
  if (!have_gnuplot) {
    html << "<p><b>gnuplot was not found</b>: install it (apt-get install gnuplot-nox) and rerun "
            "the report; the plot data are beside this page.</p>\n";
  }
  for (const Plot& plot : plots) html << FigureHtml(dir, plot, have_gnuplot);
  html << "</body></html>\n";
  const std::string index = (fs::path(dir) / "index.html").string();
  WriteFile(index, html.str());
  return index;
}

}  // namespace irdist
