#include "app/report.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <set>
#include <sstream>

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
      default:
        out += c;
    }
  }
  return out;
}

void ReplaceAll(std::string* text, const std::string& from, const std::string& to) {
  for (size_t at = 0; (at = text->find(from, at)) != std::string::npos; at += to.size()) {
    text->replace(at, from.size(), to);
  }
}

void WriteFile(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::trunc);
  out << text;
  if (!out)
    throw ReportError(path.string() + ": cannot be written; check the folder and free space.");
}

std::string ReadFile(const fs::path& path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// The default pipeline's rows: the first method, joint rows when the run has them.
std::vector<const EstimateRow*> DefaultRows(const std::vector<EstimateRow>& rows,
                                            const std::string& method) {
  bool has_joint = false;
  for (const EstimateRow& r : rows) has_joint |= (r.method == method && r.dt_ms == 0.0);
  std::vector<const EstimateRow*> out;
  for (const EstimateRow& r : rows) {
    if (r.method == method && r.ok && (!has_joint || r.dt_ms == 0.0)) out.push_back(&r);
  }
  return out;
}

double RelErrPct(const EstimateRow& r) { return 100.0 * (r.d_mm - r.true_d_mm) / r.true_d_mm; }

}  // namespace

std::vector<Plot> ValidationPlots(const std::vector<EstimateRow>& rows,
                                  const ValidationSummary& summary) {
  std::vector<Plot> plots;
  if (summary.methods.empty()) return plots;
  const std::string method = summary.methods.front().method;
  const auto main_rows = DefaultRows(rows, method);
  if (main_rows.empty()) return plots;

  {  // Fig. 10: estimated vs true distance, one series per bias current.
    std::map<long, std::vector<const EstimateRow*>> by_current;
    for (const EstimateRow* r : main_rows) by_current[std::lround(r->bias_ma)].push_back(r);
    std::ostringstream data, script;
    data << std::setprecision(10);
    script << "set xlabel 'true distance d (mm)'\nset ylabel 'estimated distance (mm)'\n"
              "set key top left\nset grid\nplot x title 'ideal' lc rgb '#888888'";
    int block = 0;
    if (by_current.size() <= 6) {
      for (const auto& [ma, rs] : by_current) {
        data << "# bias " << ma << " mA\n";
        for (const EstimateRow* r : rs) data << r->true_d_mm << ' ' << r->d_mm << '\n';
        data << "\n\n";
        script << ", '__DATA__' index " << block++ << " using 1:2 with points pt 7 ps 0.6 title '"
               << ma << " mA'";
      }
    } else {
      for (const EstimateRow* r : main_rows) data << r->true_d_mm << ' ' << r->d_mm << '\n';
      script << ", '__DATA__' using 1:2 with points pt 7 ps 0.6 title 'random currents'";
    }
    script << "\n";
    plots.push_back({"fig10_distance", "Estimated against true distance",
                     "Estimated distance (mm) against the station's distance (mm), one series per "
                     "IRED bias current (" +
                         method +
                         "). Reproduces Fig. 10 of the paper: "
                         "the estimate should not move with the current.",
                     data.str(), script.str()});
  }

  const MethodSummary& m = summary.methods.front();
  if (m.by_dt.size() >= 2) {  // Fig. 11-12: error against exposure difference.
    std::ostringstream data, script;
    for (const auto& [dt, f] : m.by_dt) {
      data << dt << ' ' << f.distance_rel_error_pct_median << ' ' << f.distance_rel_error_pct_p95
           << ' ' << f.distance_rel_error_pct_max << '\n';
    }
    script << "set xlabel 'exposure difference dt (ms)'\nset ylabel 'relative distance error (%)'\n"
              "set grid\nset key top right\n"
              "plot '__DATA__' using 1:2 with linespoints pt 7 title 'median', "
              "'' using 1:3 with linespoints pt 5 title 'p95', "
              "'' using 1:4 with linespoints pt 9 title 'max'\n";
    plots.push_back({"fig11_dt", "Error against exposure difference",
                     "Relative distance error (%) of the per-dt estimates against dt = t_n - t_r "
                     "(ms). Reproduces Fig. 11-12 of the paper (its 'bathtub' and optimum dt).",
                     data.str(), script.str()});
  }

  {  // Fig. 13: (theta, d) coloured by error, and the histogram of errors.
    std::ostringstream data, script;
    for (const EstimateRow* r : main_rows) {
      data << r->true_theta_deg << ' ' << r->true_d_mm << ' ' << std::abs(RelErrPct(*r)) << ' '
           << r->theta_deg << ' ' << r->d_mm << '\n';
    }
    script << "set xlabel 'IRED orientation theta (deg)'\nset ylabel 'distance (mm)'\nset grid\n"
              "set cblabel '|relative distance error| (%)'\nset palette rgb 33,13,10\n"
              "plot '__DATA__' using 1:2 with points pt 6 ps 1.5 lc rgb '#555555' title 'true', "
              "'' using 4:5:3 with points pt 7 ps 0.7 palette title 'estimated'\n";
    plots.push_back({"fig13_scatter", "Estimated (theta, d) against the truth",
                     "True (open circles) and estimated (filled, coloured by |relative distance "
                     "error| in %) orientation (deg) and distance (mm). Reproduces Fig. 13 of "
                     "the paper.",
                     data.str(), script.str()});
    std::vector<double> errs;
    for (const EstimateRow* r : main_rows) errs.push_back(RelErrPct(*r));
    double largest = 0.0;
    for (double e : errs) largest = std::max(largest, std::abs(e));
    const double span = std::max(0.5, std::ceil(2.0 * largest) / 2.0);
    const int bins = 20;
    std::vector<int> counts(bins, 0);
    for (double e : errs) {
      int b = static_cast<int>(std::floor((e + span) / (2.0 * span) * bins));
      counts[std::clamp(b, 0, bins - 1)]++;
    }
    std::ostringstream hist;
    for (int b = 0; b < bins; ++b) {
      hist << (-span + (b + 0.5) * 2.0 * span / bins) << ' ' << counts[b] << '\n';
    }
    std::ostringstream hs;
    hs << "set xlabel 'relative distance error (%)'\nset ylabel 'estimates'\nset grid\n"
          "set style fill solid 0.6\nset boxwidth "
       << (1.8 * span / bins)
       << "\n"
          "plot '__DATA__' using 1:2 with boxes lc rgb '#3366aa' notitle\n";
    plots.push_back({"fig13_histogram", "Histogram of distance errors",
                     "Distribution of the signed relative distance error (%). Reproduces the "
                     "histogram of Fig. 13 of the paper.",
                     hist.str(), hs.str()});
  }

  {  // Fig. 14: repetitions per angle, when a pose was repeated.
    std::map<long, std::vector<const EstimateRow*>> by_theta;
    int max_repeat = 0;
    for (const EstimateRow* r : main_rows) {
      by_theta[std::lround(r->true_theta_deg)].push_back(r);
      max_repeat = std::max(max_repeat, r->repeat);
    }
    if (max_repeat >= 2) {
      std::ostringstream data, script;
      script << "set xlabel 'repetition'\nset ylabel 'estimated distance (mm)'\nset grid\n"
                "set key outside right\nplot ";
      int block = 0;
      for (const auto& [theta, rs] : by_theta) {
        for (const EstimateRow* r : rs)
          data << r->repeat << ' ' << r->d_mm << ' ' << r->true_d_mm << '\n';
        data << "\n\n";
        script << (block ? ", " : "") << "'__DATA__' index " << block
               << " using 1:2 with points pt 7 ps 0.5 title '" << theta << " deg'";
        ++block;
      }
      script << ", '__DATA__' index 0 using 1:3 with lines lc rgb '#000000' title 'true d'\n";
      plots.push_back({"fig14_repetitions", "Repeated estimates of one pose",
                       "Estimated distance (mm) over repetitions of the same pose, one series per "
                       "orientation (deg); the black line is the station's distance. Reproduces "
                       "Fig. 14 of the paper (consistency).",
                       data.str(), script.str()});
    }
  }

  if (summary.methods.size() >= 2) {  // methods side by side
    std::ostringstream data, script;
    script << "set xlabel 'true distance (mm)'\nset ylabel 'relative distance error (%)'\n"
              "set grid\nset key outside right\nplot ";
    int block = 0;
    for (const MethodSummary& ms : summary.methods) {
      for (const EstimateRow* r : DefaultRows(rows, ms.method)) {
        data << r->true_d_mm << ' ' << RelErrPct(*r) << '\n';
      }
      data << "\n\n";
      script << (block ? ", " : "") << "'__DATA__' index " << block << " using ($1+" << (block * 10)
             << "):2 with points pt 7 ps 0.5 title '" << ms.method << "' noenhanced";
      ++block;
    }
    script << "\n";
    plots.push_back(
        {"methods", "Methods side by side",
         "Signed relative distance error (%) against the true distance (mm) for each "
         "estimation method (I0-free radiometric, I0-dependent direct model, purely "
         "geometric apparent size); series offset by 10 mm for legibility. Not a figure of "
         "the paper: the comparison NOTES.md asks for.",
         data.str(), script.str()});
  }
  return plots;
}

std::vector<Plot> CalibrationPlots(const std::vector<CalibrationPoint>& points) {
  std::vector<Plot> plots;
  if (points.empty()) return plots;
  {
    std::ostringstream data, script;
    data << std::setprecision(10);
    for (const CalibrationPoint& p : points) {
      data << p.de_measured << ' ' << p.de_model << ' ' << p.ds_measured << ' ' << p.ds_model << ' '
           << 100.0 * (p.de_model - p.de_measured) / p.de_measured << ' '
           << 100.0 * (p.ds_model - p.ds_measured) / p.ds_measured << '\n';
    }
    script
        << "set multiplot layout 2,2 title '__TITLE__'\nset grid\n"
           "set xlabel 'measured dE_{rel}'\nset ylabel 'model dE_{rel}'\n"
           "plot '__DATA__' using 1:2 with points pt 7 ps 0.4 notitle, x notitle lc rgb '#888888'\n"
           "set xlabel 'measured dSigma (normalised gray)'\n"
           "set ylabel 'model dSigma (normalised gray)'\n"
           "plot '__DATA__' using 3:4 with points pt 7 ps 0.4 notitle, x notitle lc rgb '#888888'\n"
           "set xlabel 'sample'\nset ylabel 'dE relative error (%)'\n"
           "plot '__DATA__' using 0:5 with impulses notitle\n"
           "set xlabel 'sample'\nset ylabel 'dSigma relative error (%)'\n"
           "plot '__DATA__' using 0:6 with impulses notitle\nunset multiplot\n";
    plots.push_back(
        {"fig7_fit", "Calibration fit: measured against modelled",
         "Measured against modelled differences dE_rel (dimensionless) and dSigma (gray levels "
         "normalised to full scale), and their relative errors (%) per calibration sample. "
         "Reproduces Fig. 7 of the paper (the I0-free models, Eq. 17-18). With a fixed-window "
         "ROI dE_rel is dF / A exactly: its model fits to rounding error and carries no "
         "distance information (docs/estimator.md).",
         data.str(), script.str()});
  }
  std::ostringstream data, script;
  script << "set xlabel 'distance d (mm)'\nset ylabel 'Eq. 25 polynomial (scaled)'\nset grid\n"
            "set key outside right\nset xzeroaxis lt -1\nplot ";
  int block = 0;
  for (const CalibrationPoint& p : points) {
    if (p.eq25_d_mm.empty() || block >= 8) continue;
    double scale = 0.0;
    for (double v : p.eq25_value) scale = std::max(scale, std::abs(v));
    if (scale == 0.0) scale = 1.0;
    for (size_t i = 0; i < p.eq25_d_mm.size(); ++i) {
      data << p.eq25_d_mm[i] << ' ' << p.eq25_value[i] / scale << '\n';
    }
    data << "\n\n";
    script << (block ? ", " : "") << "'__DATA__' index " << block << " using 1:2 with lines title '"
           << p.d_mm << " mm, " << p.theta_deg << " deg'";
    ++block;
  }
  if (block > 0) {
    script << "\n";
    plots.push_back({"fig8_eq25", "Eq. 25 curves",
                     "The Eq. 25 cubic in D, evaluated along d (mm) and scaled to unit maximum, "
                     "for a few calibration samples; its zero crossing is the distance root. "
                     "Reproduces Fig. 8 of the paper. Eq. 25 is only the paper's initialiser: "
                     "with a degenerate E equation its roots can miss the true distance, which is "
                     "why the default estimator solves the Sigma and geometric equations jointly "
                     "(docs/estimator.md).",
                     data.str(), script.str()});
  }
  return plots;
}

std::string WriteReport(const std::string& dir, const std::string& title,
                        const std::string& summary_text, const std::vector<Plot>& plots) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw ReportError(dir + ": cannot create the report folder: " + ec.message());
  const bool have_gnuplot = std::system("command -v gnuplot >/dev/null 2>&1") == 0;
  std::ostringstream html;
  html << "<!DOCTYPE html>\n<html><head><meta charset='utf-8'><title>" << HtmlEscape(title)
       << "</title>\n<style>body{font-family:sans-serif;max-width:980px;margin:2em auto;}"
          "figure{margin:2em 0;}figcaption{color:#333;font-size:0.95em;}"
          "pre{background:#f4f4f4;padding:1em;white-space:pre-wrap;}</style></head><body>\n"
       << "<h1>" << HtmlEscape(title) << "</h1>\n<pre>" << HtmlEscape(summary_text) << "</pre>\n";
  if (!have_gnuplot) {
    html << "<p><b>gnuplot was not found</b>: install it (apt-get install gnuplot-nox) and rerun "
            "the report; the plot data are beside this page.</p>\n";
  }
  for (const Plot& plot : plots) {
    const fs::path base = fs::path(dir) / plot.name;
    WriteFile(base.string() + ".dat", plot.data);
    std::string body = plot.script;
    ReplaceAll(&body, "__DATA__", plot.name + ".dat");
    ReplaceAll(&body, "__TITLE__", plot.title);
    const bool multiplot = body.find("multiplot") != std::string::npos;
    std::ostringstream gp;
    gp << "set terminal svg size " << (multiplot ? "900,720" : "760,480")
       << " dynamic enhanced font 'sans,11'\nset output '" << plot.name << ".svg'\n"
       << (multiplot ? std::string() : "set title '" + plot.title + "'\n") << body;
    WriteFile(base.string() + ".gp", gp.str());
    html << "<figure id='" << plot.name << "'><h2>" << HtmlEscape(plot.title) << "</h2>\n";
    bool drawn = false;
    if (have_gnuplot) {
      const std::string cmd =
          "cd '" + dir + "' && gnuplot '" + plot.name + ".gp' 2>'" + plot.name + ".log'";
      drawn = std::system(cmd.c_str()) == 0 && fs::exists(base.string() + ".svg");
    }
    if (drawn) {
      std::string svg = ReadFile(base.string() + ".svg");
      const size_t start = svg.find("<svg");
      html << (start == std::string::npos ? svg : svg.substr(start)) << "\n";
    } else {
      html << "<p>(not drawn: see " << plot.name << ".gp, " << plot.name << ".dat"
           << (have_gnuplot ? " and " + plot.name + ".log" : std::string()) << ")</p>\n";
    }
    html << "<figcaption>" << HtmlEscape(plot.caption) << "</figcaption></figure>\n";
  }
  html << "</body></html>\n";
  const std::string index = (fs::path(dir) / "index.html").string();
  WriteFile(index, html.str());
  return index;
}

}  // namespace irdist
