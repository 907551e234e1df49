#include "app/reports/validation_plots.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <map>
#include <sstream>

namespace irdist {
namespace {

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
  s << kPlotStyle << "set multiplot\nset lmargin at screen 0.10\nset rmargin at screen 0.76\n"
    << "set origin 0,0.42\nset size 1,0.58\nset xlabel 'true distance d (mm)'\n"
    << "set ylabel 'estimated distance (mm)'\n"
    << "plot x title 'estimate = truth' lc rgb '#555555' dt 2";
  int i = 0;
  for (const auto& [ma, rs] : by_current) {
    s << ", '__DATA__' index " << i << " using 1:2 with points pt " << SeriesPointType(i)
      << " ps 0.6 lc rgb '" << SeriesColour(i) << "' title '" << ma << " mA'";
    ++i;
  }
  s << "\nset origin 0,0\nset size 1,0.42\nset ylabel 'estimate - truth (mm)'\n"
    << "plot 0 title 'truth' lc rgb '#000000' lw 1.5";
  i = 0;
  for (const auto& [ma, rs] : by_current) {
    s << ", '__DATA__' index " << i << " using 1:3 with points pt " << SeriesPointType(i)
      << " ps 0.5 lc rgb '" << SeriesColour(i) << "' notitle, '__DATA__' index " << (n + i)
      << " using 1:2 with lines lw 1.5 lc rgb '" << SeriesColour(i) << "' title 'mean, " << ma
      << " mA'";
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
  s << kPlotStyle << "set multiplot\nset lmargin at screen 0.10\nset rmargin at screen 0.76\n"
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
  s << kPlotStyle << "set xlabel 'exposure difference dt = t_n - t_r (ms)'\n"
    << "set ylabel '|relative distance error| (%)'\nset yrange [0:*]\n";
  if (m.best_dt_ms) {
    s << "set arrow from " << *m.best_dt_ms << ", graph 0 to " << *m.best_dt_ms
      << ", graph 1 nohead lc rgb '#000000' dt 2\n";
  }
  s << "plot '__DATA__' using 1:2 with linespoints pt 7 lc rgb '" << SeriesColour(0)
    << "' title 'median', '' using 1:3 with linespoints pt 5 lc rgb '" << SeriesColour(1)
    << "' title 'p95', '' using 1:4 with linespoints pt 9 lc rgb '" << SeriesColour(2)
    << "' title 'max'";
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
  s << kPlotStyle << "set xlabel 'IRED orientation theta (deg)'\n"
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
  s << kPlotStyle << "set xlabel 'signed relative distance error (%)'\n"
    << "set ylabel 'estimates (count)'\nset yrange [0:*]\nset xrange [" << -span << ":" << span
    << "]\nset style fill solid 0.6\nset boxwidth " << (1.8 * span / bins) << "\n"
    << "set arrow from 0, graph 0 to 0, graph 1 nohead lc rgb '#000000' lw 1.5\n"
    << "plot '__DATA__' using 1:2 with boxes lc rgb '" << SeriesColour(0)
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
  s << kPlotStyle << "set xlabel 'repetition (points of a pose spread by up to +-0.3)'\n"
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
    s << ", '__DATA__' index " << i << " using 1:2 with points pt " << SeriesPointType(i)
      << " ps 0.6 lc rgb '" << SeriesColour(i) << "' title '" << pose.first << " mm, "
      << pose.second << " deg'";
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
      << " using 1:2 with points pt 7 ps 0.5 lc rgb '" << SeriesColour(i) << "' notitle\n";
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

}  // namespace irdist
