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

#include "acquisition/recording.h"
#include "base/process.h"
#include "base/regular_file.h"

#ifndef IRDIST_VERSION
#define IRDIST_VERSION "unknown"
#endif

namespace irdist {
namespace {

namespace fs = std::filesystem;

// Series colours (colour-blind safe, Okabe-Ito) and point types, by series index.
const char* const kColours[] = {"#0072B2", "#D55E00", "#009E73", "#CC79A7",
                                "#E69F00", "#56B4E9", "#000000", "#999999"};
constexpr int kNumColours = 8;
const int kPointTypes[] = {7, 5, 9, 11, 13, 6, 4, 8};

std::string Colour(int i) { return kColours[i % kNumColours]; }
int PointType(int i) { return kPointTypes[i % kNumColours]; }

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

void ReplaceAll(std::string* text, const std::string& from, const std::string& to) {
  for (size_t at = 0; (at = text->find(from, at)) != std::string::npos; at += to.size()) {
    text->replace(at, from.size(), to);
  }
}

// What to do when a report file cannot be written: the disk is the usual cause.
std::string WriteFix(const fs::path& path) {
  return "; free disk space (df -h " + path.parent_path().string() +
         ") or fix the folder's permissions, then run the command again";
}

// Whole or not at all (temporary file, sync, rename): a full disk never leaves a cut file.
void WriteFile(const fs::path& path, const std::string& text) {
  std::string why;
  if (!WriteRegularFile(path.string(), text, &why)) {
    throw ReportError(path.string() + ": " + why + WriteFix(path));
  }
}

std::string ReadFile(const fs::path& path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string Fixed(double v, int digits) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << v;
  return s.str();
}

// A tick step of 1, 2 or 5 times a power of ten that puts at most `most_labels` labels on `span`
// (figures readable at 1280 px: gnuplot's own choice runs labels together on small panels).
double TickStep(double span, int most_labels) {
  if (!(span > 0.0) || !std::isfinite(span)) return 1.0;
  const double raw = span / most_labels;
  const double decade = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0}) {
    if (m * decade >= raw) return m * decade;
  }
  return 10.0 * decade;
}

// "set xtics STEP" (or ytics) for values spanning [lowest, highest], at most `most_labels` labels.
std::string TicsFor(const char* axis, const std::vector<double>& values, int most_labels) {
  if (values.empty()) return std::string("set ") + axis + "tics\n";
  const auto [lowest, highest] = std::minmax_element(values.begin(), values.end());
  std::ostringstream s;
  s << "set " << axis << "tics " << TickStep(*highest - *lowest, most_labels) << "\n";
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

// Axis padding so that no point sits on the frame, and the legend outside the data.
const char* const kCommonStyle =
    "set grid\nset key outside right top vertical Left reverse noenhanced\n"
    "set offsets graph 0.04, graph 0.04, graph 0.06, graph 0.06\n";

// ---- Fig. 10: estimated against true distance, residual per current --------------------------

using ByCurrent = std::map<long, std::vector<const EstimateRow*>>;

// Block per current: true d, estimate, residual (mm); then per current the mean residual at
// each true distance (the line that shows whether the current moves the estimate).
std::string Fig10Data(const ByCurrent& by_current) {
  std::ostringstream data;
  data << std::setprecision(10);
  for (const auto& [ma, rs] : by_current) {
    data << "# bias " << ma << " mA: true_d_mm d_mm residual_mm\n";
    for (const EstimateRow* r : rs) {
      data << r->true_d_mm << ' ' << r->d_mm << ' ' << r->d_mm - r->true_d_mm << '\n';
    }
    data << "\n\n";
  }
  for (const auto& [ma, rs] : by_current) {
    std::map<double, std::pair<double, int>> sums;
    for (const EstimateRow* r : rs) {
      auto& s = sums[r->true_d_mm];
      s.first += r->d_mm - r->true_d_mm;
      s.second += 1;
    }
    data << "# bias " << ma << " mA: true_d_mm mean_residual_mm\n";
    for (const auto& [d, s] : sums) data << d << ' ' << s.first / s.second << '\n';
    data << "\n\n";
  }
  return data.str();
}

std::string Fig10Script(const ByCurrent& by_current) {
  const int n = static_cast<int>(by_current.size());
  std::ostringstream s;
  s << kCommonStyle << "set multiplot\nset lmargin at screen 0.10\nset rmargin at screen 0.76\n"
    << "set origin 0,0.42\nset size 1,0.58\nset xlabel 'true distance d (mm)'\n"
    << "set ylabel 'estimated distance (mm)'\n"
    << "plot x title 'estimate = truth' lc rgb '#555555' dt 2";
  int i = 0;
  for (const auto& [ma, rs] : by_current) {
    s << ", '__DATA__' index " << i << " using 1:2 with points pt " << PointType(i)
      << " ps 0.6 lc rgb '" << Colour(i) << "' title '" << ma << " mA'";
    ++i;
  }
  s << "\nset origin 0,0\nset size 1,0.42\nset ylabel 'estimate - truth (mm)'\n"
    << "plot 0 title 'truth' lc rgb '#000000' lw 1.5";
  i = 0;
  for (const auto& [ma, rs] : by_current) {
    s << ", '__DATA__' index " << i << " using 1:3 with points pt " << PointType(i)
      << " ps 0.5 lc rgb '" << Colour(i) << "' notitle, '__DATA__' index " << (n + i)
      << " using 1:2 with lines lw 1.5 lc rgb '" << Colour(i) << "' title 'mean, " << ma << " mA'";
    ++i;
  }
  s << "\nunset multiplot\n";
  return s.str();
}

// Random currents (more than 6): one series, the residual coloured by the current.
Plot Fig10RandomCurrents(const std::vector<const EstimateRow*>& rows) {
  std::ostringstream data, s;
  data << std::setprecision(10);
  for (const EstimateRow* r : rows) {
    data << r->true_d_mm << ' ' << r->d_mm << ' ' << r->d_mm - r->true_d_mm << ' ' << r->bias_ma
         << '\n';
  }
  s << kCommonStyle << "set multiplot\nset lmargin at screen 0.10\nset rmargin at screen 0.76\n"
    << "set origin 0,0.42\nset size 1,0.58\nset xlabel 'true distance d (mm)'\n"
    << "set ylabel 'estimated distance (mm)'\nset cblabel 'bias current (mA)'\n"
    << "plot x title 'estimate = truth' lc rgb '#555555' dt 2, '__DATA__' using 1:2:4 with "
       "points pt 7 ps 0.6 palette title 'estimate'\n"
    << "set origin 0,0\nset size 1,0.42\nset ylabel 'estimate - truth (mm)'\n"
    << "plot 0 title 'truth' lc rgb '#000000' lw 1.5, '__DATA__' using 1:3:4 with points pt 7 "
       "ps 0.5 palette title 'residual'\nunset multiplot\n";
  return {"", "", "", data.str(), s.str(), 900, 620};
}

Plot Fig10(const std::vector<const EstimateRow*>& rows, const std::string& method) {
  ByCurrent by_current;
  for (const EstimateRow* r : rows) by_current[std::lround(r->bias_ma)].push_back(r);
  Plot p = by_current.size() <= 6
               ? Plot{"", "", "", Fig10Data(by_current), Fig10Script(by_current), 900, 620}
               : Fig10RandomCurrents(rows);
  p.name = "fig10_distance";
  p.title = "Estimated against true distance, and the residual per bias current";
  p.caption =
      "Top: estimated distance (mm) against the station's distance (mm), one colour per IRED "
      "bias current (mA), method " +
      method +
      "; the dashed line is estimate = truth. Bottom: "
      "the residual, estimate - truth (mm), against the true distance; the line of each current "
      "joins its mean residual at each distance, the black line at 0 is the truth. The estimate "
      "is independent of the current when the lines lie on each other. Reproduces Fig. 10 of "
      "the paper.";
  return p;
}

// ---- Fig. 11-12: error against the exposure difference ----------------------------------------

Plot Fig11(const MethodSummary& m) {
  std::ostringstream data, s;
  for (const auto& [dt, f] : m.by_dt) {
    data << dt << ' ' << f.distance_rel_error_pct_median << ' ' << f.distance_rel_error_pct_p95
         << ' ' << f.distance_rel_error_pct_max << '\n';
  }
  s << kCommonStyle << "set xlabel 'exposure difference dt = t_n - t_r (ms)'\n"
    << "set ylabel '|relative distance error| (%)'\nset yrange [0:*]\n";
  if (m.best_dt_ms) {
    s << "set arrow from " << *m.best_dt_ms << ", graph 0 to " << *m.best_dt_ms
      << ", graph 1 nohead lc rgb '#000000' dt 2\n";
  }
  s << "plot '__DATA__' using 1:2 with linespoints pt 7 lc rgb '" << Colour(0)
    << "' title 'median', '' using 1:3 with linespoints pt 5 lc rgb '" << Colour(1)
    << "' title 'p95', '' using 1:4 with linespoints pt 9 lc rgb '" << Colour(2) << "' title 'max'";
  if (m.best_dt_ms) s << ", NaN with lines lc rgb '#000000' dt 2 title 'best dt'";
  s << "\n";
  return {"fig11_dt", "Error against exposure difference",
          "Median, 95th percentile and largest |relative distance error| (%) of the per-dt "
          "estimates (method " +
              m.method +
              ") against dt = t_n - t_r (ms); the dashed line "
              "marks the dt with the smallest median. Reproduces Fig. 11-12 of the paper (its "
              "'bathtub' and optimum dt).",
          data.str(), s.str()};
}

// ---- Fig. 13: (theta, d) and the histogram ------------------------------------------------------

Plot Fig13Scatter(const std::vector<const EstimateRow*>& rows) {
  std::ostringstream data, s;
  for (const EstimateRow* r : rows) {
    data << r->true_theta_deg << ' ' << r->true_d_mm << ' ' << std::abs(RelErrPct(*r)) << ' '
         << r->theta_deg << ' ' << r->d_mm << '\n';
  }
  s << kCommonStyle << "set xlabel 'IRED orientation theta (deg)'\n"
    << "set ylabel 'distance d (mm)'\nset cblabel '|relative distance error| (%)'\n"
    << "set palette rgb 33,13,10\nset colorbox user origin screen 0.80,0.12 size screen "
       "0.025,0.5\nset rmargin at screen 0.72\n"
    << "plot '__DATA__' using 1:2:($4-$1):($5-$2) with vectors nohead lc rgb '#bbbbbb' "
       "title 'truth to estimate', "
       "'' using 1:2 with points pt 6 ps 1.6 lc rgb '#000000' title 'truth', "
       "'' using 4:5:3 with points pt 7 ps 0.7 palette title 'estimate'\n";
  return {"fig13_scatter", "Estimated (theta, d) against the truth",
          "True poses (open black circles) and estimates (filled, coloured by |relative "
          "distance error| in %), orientation theta (deg) and distance d (mm); a grey segment "
          "joins each estimate to its truth. Reproduces Fig. 13 of the paper.",
          data.str(), s.str()};
}

Plot Fig13Histogram(const std::vector<const EstimateRow*>& rows) {
  double largest = 0.0;
  for (const EstimateRow* r : rows) largest = std::max(largest, std::abs(RelErrPct(*r)));
  const double span = std::max(0.5, std::ceil(2.0 * largest) / 2.0);
  const int bins = 20;
  std::vector<int> counts(bins, 0);
  for (const EstimateRow* r : rows) {
    const int b = static_cast<int>(std::floor((RelErrPct(*r) + span) / (2.0 * span) * bins));
    counts[std::clamp(b, 0, bins - 1)]++;
  }
  std::ostringstream data, s;
  for (int b = 0; b < bins; ++b) {
    data << (-span + (b + 0.5) * 2.0 * span / bins) << ' ' << counts[b] << '\n';
  }
  s << kCommonStyle << "set xlabel 'signed relative distance error (%)'\n"
    << "set ylabel 'estimates (count)'\nset yrange [0:*]\nset xrange [" << -span << ":" << span
    << "]\nset style fill solid 0.6\nset boxwidth " << (1.8 * span / bins) << "\n"
    << "set arrow from 0, graph 0 to 0, graph 1 nohead lc rgb '#000000' lw 1.5\n"
    << "plot '__DATA__' using 1:2 with boxes lc rgb '" << Colour(0)
    << "' title 'estimates', NaN with lines lc rgb '#000000' lw 1.5 title 'truth (0 %)'\n";
  return {"fig13_histogram", "Histogram of distance errors",
          "Distribution of the signed relative distance error (%), estimate against the "
          "station's distance; the black line at 0 is the truth. Reproduces the histogram of "
          "Fig. 13 of the paper.",
          data.str(), s.str()};
}

// ---- Fig. 14: repetitions ----------------------------------------------------------------------

using ByPose = std::map<std::pair<long, long>, std::vector<const EstimateRow*>>;

// At most `most` poses, evenly spread over the (distance, angle) order, so that the legend stays
// readable and both ends are shown.
ByPose SpreadPoses(const ByPose& by_pose, size_t most) {
  if (by_pose.size() <= most) return by_pose;
  std::vector<ByPose::const_iterator> all;
  for (auto it = by_pose.begin(); it != by_pose.end(); ++it) all.push_back(it);
  ByPose out;
  for (size_t i = 0; i < most; ++i) {
    out.insert(*all[(i * (all.size() - 1) + (most - 1) / 2) / (most - 1)]);
  }
  return out;
}

Plot Fig14(const ByPose& by_pose, size_t total_poses) {
  std::ostringstream data, s;
  int max_repeat = 1;
  for (const auto& [pose, rs] : by_pose) {
    for (const EstimateRow* r : rs) max_repeat = std::max(max_repeat, r->repeat);
  }
  // Whole repetitions, at most about 10 labels counting the ends gnuplot adds (a run of 110
  // repetitions labelled each one).
  s << kCommonStyle << "set xlabel 'repetition (points of a pose spread by up to +-0.3)'\n"
    << "set ylabel 'estimate - truth (mm)'\nset xtics 0, "
    << std::max(1.0, TickStep(max_repeat, 8)) << "\nplot 0 title 'truth' lc rgb "
       "'#000000' lw 1.5";
  const int n = static_cast<int>(by_pose.size());
  int i = 0;
  for (const auto& [pose, rs] : by_pose) {
    // Jitter on the categorical repetition axis so that poses do not hide each other.
    const double jitter = n > 1 ? -0.3 + 0.6 * i / (n - 1) : 0.0;
    for (const EstimateRow* r : rs) {
      data << r->repeat + jitter << ' ' << r->d_mm - r->true_d_mm << '\n';
    }
    data << "\n\n";
    s << ", '__DATA__' index " << i << " using 1:2 with points pt " << PointType(i)
      << " ps 0.6 lc rgb '" << Colour(i) << "' title '" << pose.first << " mm, " << pose.second
      << " deg'";
    ++i;
  }
  s << "\n";
  return {"fig14_repetitions", "Repeated estimates of one pose",
          "Deviation of the estimated distance from the station's distance (mm) over the "
          "repetitions (numbered from 0) of each pose (true distance mm, orientation deg; " +
              std::to_string(by_pose.size()) + " of the " + std::to_string(total_poses) +
              " poses); the black line at 0 is the truth. Reproduces Fig. 14 of the paper "
              "(consistency).",
          data.str(), s.str()};
}

// ---- Methods side by side ----------------------------------------------------------------------

Plot MethodsPlot(const std::vector<EstimateRow>& rows, const ValidationSummary& summary) {
  std::ostringstream data, s;
  double largest = 0.0;
  for (const MethodSummary& ms : summary.methods) {
    for (const EstimateRow* r : DefaultRows(rows, ms.method)) {
      data << r->true_d_mm << ' ' << RelErrPct(*r) << '\n';
      largest = std::max(largest, std::abs(RelErrPct(*r)));
    }
    data << "\n\n";
  }
  const double y = largest > 0.0 ? 1.15 * largest : 1.0;
  const int n = static_cast<int>(summary.methods.size());
  s << "set grid\nset offsets graph 0.04, graph 0.04, 0, 0\nset yrange [" << -y << ":" << y
    << "]\nset multiplot layout " << n << ",1\nset lmargin at screen 0.10\n"
    << "set rmargin at screen 0.96\nset ylabel 'error (%)'\n";
  for (int i = 0; i < n; ++i) {
    s << "set xlabel " << (i + 1 == n ? "'true distance d (mm)'" : "''") << "\n"
      << "set label 1 '" << summary.methods[i].method << "' at graph 0.01, graph 0.9 left "
      << "front noenhanced\nplot 0 notitle lc rgb '#000000' lw 1.5, '__DATA__' index " << i
      << " using 1:2 with points pt 7 ps 0.5 lc rgb '" << Colour(i) << "' notitle\n";
  }
  s << "unset multiplot\n";
  Plot p{"methods", "Methods side by side",
         "Signed relative distance error (%) against the true distance (mm), one panel per "
         "estimation method (named at each panel's top left; I0-free radiometric, "
         "I0-dependent direct model, purely geometric apparent size), on a common error scale; "
         "the black line at 0 is the truth. Not a figure of the paper: the comparison of the "
         "methods on the same brackets.",
         data.str(), s.str()};
  p.height_px = 60 + 190 * n;
  return p;
}

}  // namespace

std::vector<Plot> ValidationPlots(const std::vector<EstimateRow>& rows,
                                  const ValidationSummary& summary) {
  std::vector<Plot> plots;
  if (summary.methods.empty()) return plots;
  const MethodSummary& m = summary.methods.front();
  const auto main_rows = DefaultRows(rows, m.method);
  if (main_rows.empty()) return plots;
  plots.push_back(Fig10(main_rows, m.method));
  if (m.by_dt.size() >= 2) plots.push_back(Fig11(m));
  plots.push_back(Fig13Scatter(main_rows));
  plots.push_back(Fig13Histogram(main_rows));
  ByPose by_pose;
  int max_repeat = 0;
  for (const EstimateRow* r : main_rows) {
    by_pose[{std::lround(r->true_d_mm), std::lround(r->true_theta_deg)}].push_back(r);
    max_repeat = std::max(max_repeat, r->repeat);
  }
  if (max_repeat >= 2) plots.push_back(Fig14(SpreadPoses(by_pose, 8), by_pose.size()));
  if (summary.methods.size() >= 2) plots.push_back(MethodsPlot(rows, summary));
  return plots;
}

namespace {

// ---- Fig. 7: measured against modelled ---------------------------------------------------------

std::string Fig7Data(const std::vector<CalibrationPoint>& points) {
  std::ostringstream data;
  data << std::setprecision(10);
  data << "# de_measured de_model ds_measured ds_model de_err_pct ds_err_pct d_mm\n";
  for (const CalibrationPoint& p : points) {
    data << p.de_measured << ' ' << p.de_model << ' ' << p.ds_measured << ' ' << p.ds_model << ' '
         << 100.0 * (p.de_model - p.de_measured) / p.de_measured << ' '
         << 100.0 * (p.ds_model - p.ds_measured) / p.ds_measured << ' ' << p.d_mm << '\n';
  }
  return data.str();
}

// The dE panels: the fit and its relative errors, or, when the fit is not one, the measured dE
// against the distance and a panel that says why no residual is drawn.
std::string Fig7EPanels(const std::string& e_problem, bool top) {
  std::ostringstream s;
  if (e_problem.empty()) {
    if (top) {
      return "set xlabel 'measured dE_{rel}'\nset ylabel 'model dE_{rel}'\n"
             "plot x notitle lc rgb '#555555' dt 2, '__DATA__' using 1:2 with points pt 7 ps "
             "0.4 lc rgb '" +
             Colour(0) + "' notitle\n";
    }
    return "set xlabel 'calibration sample (index)'\nset ylabel 'dE_{rel} model error (%)'\n"
           "plot 0 notitle lc rgb '#000000', '__DATA__' using 0:5 with impulses lc rgb '" +
           Colour(0) + "' notitle\n";
  }
  if (top) {
    return "set xlabel 'true distance d (mm)'\nset ylabel 'measured dE_{rel}'\n"
           "plot '__DATA__' using 7:1 with points pt 7 ps 0.4 lc rgb '#777777' notitle\n";
  }
  std::string reason = e_problem;  // inside a double-quoted gnuplot string: no quote, no escape
  ReplaceAll(&reason, "\"", "");
  ReplaceAll(&reason, "\\", "");
  // Wrap the reason at about 45 characters for the text panel.
  std::string wrapped;
  size_t line = 0;
  for (char c : reason) {
    if (c == ' ' && line > 55) {
      wrapped += "\\n";
      line = 0;
      continue;
    }
    wrapped += c;
    ++line;
  }
  s << "unset grid\nunset border\nunset xtics\nunset ytics\nset xlabel ''\nset ylabel ''\n"
    << "set label 2 \"The dE_rel model is not a fit:\\n"
    << wrapped
    << "\\nIts residuals measure nothing and are not plotted.\" at graph 0.02, graph 0.75 left "
       "noenhanced\nplot [0:1][0:1] NaN notitle\nunset label 2\nset border\nset xtics\n"
       "set ytics\nset grid\n";
  return s.str();
}

// Each Fig. 7 panel's ticks, chosen for its data: at most about 6 labels on a panel of about
// 450 px (gnuplot's own steps ran 4-digit labels together at 1280 px).
struct Fig7Tics {
  std::string e_top, e_bottom, sigma_top, sigma_bottom;
};

Fig7Tics Fig7TicsFor(const std::vector<CalibrationPoint>& points, bool e_fit) {
  constexpr int kMostLabels = 5;
  std::vector<double> de, de_both, ds_both, de_err, ds_err, d_mm, index;
  for (const CalibrationPoint& p : points) {
    de.push_back(p.de_measured);
    de_both.insert(de_both.end(), {p.de_measured, p.de_model});
    ds_both.insert(ds_both.end(), {p.ds_measured, p.ds_model});
    de_err.push_back(100.0 * (p.de_model - p.de_measured) / p.de_measured);
    ds_err.push_back(100.0 * (p.ds_model - p.ds_measured) / p.ds_measured);
    d_mm.push_back(p.d_mm);
    index.push_back(static_cast<double>(index.size()));
  }
  const auto tics = [](const std::vector<double>& x, const std::vector<double>& y) {
    return TicsFor("x", x, kMostLabels) + TicsFor("y", y, kMostLabels);
  };
  return {e_fit ? tics(de_both, de_both) : tics(d_mm, de), tics(index, de_err),
          tics(ds_both, ds_both), tics(index, ds_err)};
}

std::string Fig7Script(const std::string& e_problem, const std::vector<CalibrationPoint>& points) {
  const Fig7Tics tics = Fig7TicsFor(points, e_problem.empty());
  std::ostringstream s;
  s << "set multiplot layout 2,2\nset grid\nset offsets graph 0.04, graph 0.04, graph 0.06, "
       "graph 0.06\n"
    << tics.e_top << Fig7EPanels(e_problem, true) << tics.sigma_top
    << "set xlabel 'measured dSigma (normalised gray)'\n"
       "set ylabel 'model dSigma (normalised gray)'\n"
       "plot x notitle lc rgb '#555555' dt 2, '__DATA__' using 3:4 with points pt 7 ps 0.4 lc "
       "rgb '"
    << Colour(1) << "' notitle\n"
    << tics.e_bottom << Fig7EPanels(e_problem, false) << tics.sigma_bottom
    << "set xlabel 'calibration sample (index)'\nset ylabel 'dSigma model error (%)'\n"
       "plot 0 notitle lc rgb '#000000', '__DATA__' using 0:6 with impulses lc rgb '"
    << Colour(1) << "' notitle\nunset multiplot\n";
  return s.str();
}

Plot Fig7(const std::vector<CalibrationPoint>& points, const std::string& e_problem,
          const std::string& sigma_problem) {
  Plot p{"fig7_fit",
         "Calibration fit: measured against modelled",
         "",
         Fig7Data(points),
         Fig7Script(e_problem, points),
         900,
         720};
  p.caption =
      "Right: measured against modelled dSigma (gray levels normalised to full scale; the "
      "dashed line is model = measured) and the model's relative error (%) per calibration "
      "sample" +
      (sigma_problem.empty()
           ? std::string(". ")
           : " (the dSigma fit is " + sigma_problem +
                 ": small residuals, but some of its coefficients are poorly determined). ") +
      "Left: ";
  p.caption += e_problem.empty()
                   ? "the same for dE_rel (dimensionless). "
                   : "the measured dE_rel (dimensionless) against the true distance (mm); its "
                     "model is not drawn as a fit because it is " +
                         e_problem + ". ";
  p.caption += "Reproduces Fig. 7 of the paper (the I0-free models, Eq. 17-18).";
  return p;
}

// ---- Fig. 8: Eq. 25 curves ---------------------------------------------------------------------

// Where a sampled curve changes sign (linear interpolation), in mm.
std::vector<double> ZeroCrossings(const CalibrationPoint& p) {
  std::vector<double> roots;
  for (size_t i = 1; i < p.eq25_value.size(); ++i) {
    const double a = p.eq25_value[i - 1], b = p.eq25_value[i];
    if (a == 0.0) roots.push_back(p.eq25_d_mm[i - 1]);
    if ((a < 0.0) != (b < 0.0) && a != 0.0 && b != 0.0) {
      roots.push_back(p.eq25_d_mm[i - 1] + (p.eq25_d_mm[i] - p.eq25_d_mm[i - 1]) * a / (a - b));
    }
  }
  return roots;
}

std::string CurveLabel(const CalibrationPoint& p) {
  std::ostringstream s;
  s << "true d " << Fixed(p.d_mm, 0) << " mm, " << Fixed(p.theta_deg, 0) << " deg: ";
  const std::vector<double> roots = ZeroCrossings(p);
  if (roots.empty()) return s.str() + "no zero crossing";
  s << (roots.size() == 1 ? "crosses 0 at " : "crosses 0 at ");
  for (size_t i = 0; i < roots.size(); ++i) s << (i ? ", " : "") << Fixed(roots[i], 0);
  return s.str() + " mm";
}

std::optional<Plot> Fig8(const std::vector<CalibrationPoint>& points) {
  std::ostringstream data, s, plot;
  s << kCommonStyle << "set key below vertical Left reverse\n"
    << "set xlabel 'distance d (mm)'\nset ylabel 'Eq. 25 polynomial c - a (scaled to unit "
       "maximum)'\nset xzeroaxis lt -1\n";
  int block = 0;
  for (const CalibrationPoint& p : points) {
    if (p.eq25_d_mm.empty() || block >= 6) continue;
    double scale = 0.0;
    for (double v : p.eq25_value) scale = std::max(scale, std::abs(v));
    if (scale == 0.0) scale = 1.0;
    for (size_t i = 0; i < p.eq25_d_mm.size(); ++i) {
      data << p.eq25_d_mm[i] << ' ' << p.eq25_value[i] / scale << '\n';
    }
    data << "\n\n";
    s << "set arrow from " << p.d_mm << ", graph 0 to " << p.d_mm << ", graph 1 nohead lc rgb '"
      << Colour(block) << "' dt 2 lw 1.5\n";
    plot << (block ? ", " : "plot ") << "'__DATA__' index " << block
         << " using 1:2 with lines lw 1.5 lc rgb '" << Colour(block) << "' title '" << CurveLabel(p)
         << "'";
    ++block;
  }
  if (block == 0) return std::nullopt;
  s << plot.str()
    << ", NaN with lines dt 2 lc rgb '#000000' title 'dashed: the true distance of "
       "the curve of the same colour'\n";
  Plot fig{"fig8_eq25", "Eq. 25 curves", "", data.str(), s.str(), 900, 560};
  fig.caption =
      "The Eq. 25 polynomial c - a in D (the Sigma equation's polynomial minus the E "
      "equation's, each normalised), evaluated along the distance d (mm) at the sample's true "
      "orientation and measured differences, scaled to unit maximum, for a few calibration "
      "samples. The dashed vertical line of the same colour marks the sample's true distance; "
      "the legend gives where each curve crosses zero (Eq. 25's distance roots). A root near "
      "the dashed line is a root at the truth; a curve whose roots miss it shows Eq. 25 failing "
      "for that sample (as it does when the E model is degenerate), which is why the default "
      "estimator solves the Sigma and geometric equations jointly and uses Eq. 25 only to "
      "start. Reproduces Fig. 8 of the paper.";
  return fig;
}

}  // namespace

std::string UnreliableFitReason(const FittedModel& model) {
  using T = FitSummary::Termination;
  if (model.degenerate) return "degenerate (dE proportional to dF: the E equation repeats F's)";
  if (model.summary.termination == T::kDegenerate) {
    return "degenerate (" + model.summary.message + ")";
  }
  if (model.summary.termination == T::kIllConditioned) {
    std::ostringstream c;
    c << std::setprecision(2) << model.summary.condition_number;
    return "ill-conditioned (condition number " + c.str() + ")";
  }
  return "";
}

std::vector<Plot> CalibrationPlots(const std::vector<CalibrationPoint>& points,
                                   const CalibrationModel& model) {
  std::vector<Plot> plots;
  if (points.empty()) return plots;
  const FittedModel* free_e = model.Find(ModelKind::kFreeE);
  const FittedModel* free_s = model.Find(ModelKind::kFreeSigma);
  plots.push_back(Fig7(points, free_e != nullptr ? UnreliableFitReason(*free_e) : "",
                       free_s != nullptr ? UnreliableFitReason(*free_s) : ""));
  if (std::optional<Plot> fig8 = Fig8(points)) plots.push_back(std::move(*fig8));
  return plots;
}

namespace {

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
    << "; |relative distance error| median " << Fixed(f.distance_rel_error_pct_median, 2)
    << " %, p95 " << Fixed(f.distance_rel_error_pct_p95, 2) << " %, max "
    << Fixed(f.distance_rel_error_pct_max, 2) << " %";
  return s.str();
}

// "converged, 72 samples, mean |error| 0.095 %" or "72 samples, degenerate (...)".
std::string FitText(const FittedModel& m) {
  std::ostringstream s;
  const std::string reason = UnreliableFitReason(m);
  if (reason.empty()) {
    s << ToString(m.summary.termination) << ", " << m.summary.samples << " samples, mean |error| "
      << Fixed(100.0 * m.summary.mean_relative_error, 3) << " %";
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
    fields.push_back({"fit geometric",
                      ToString(model.geometric.summary.termination) +
                          std::string(", mean |error| ") +
                          Fixed(100.0 * model.geometric.summary.mean_relative_error, 3) + " %"});
  }
  fields.push_back({"calibrated range", Fixed(model.ranges.d_min_mm, 0) + " - " +
                                            Fixed(model.ranges.d_max_mm, 0) + " mm, " +
                                            Fixed(model.ranges.theta_min_deg, 0) + " - " +
                                            Fixed(model.ranges.theta_max_deg, 0) + " deg"});
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

}  // namespace

ReportFields ValidationReportFields(const std::map<std::string, std::string>& context,
                                    const ValidationSummary& summary,
                                    const std::map<std::string, CrbFigures>& crb) {
  ReportFields fields;
  const auto recording = context.find("recording");
  if (recording != context.end()) fields = RecordingReportFields(recording->second);
  for (const auto& [key, value] : context) {  // the context wins over the recording's copy
    auto same =
        std::find_if(fields.begin(), fields.end(), [&](const auto& f) { return f.first == key; });
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
  header.push_back({"report written", NowUtc() + " by irdist " IRDIST_VERSION});
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
