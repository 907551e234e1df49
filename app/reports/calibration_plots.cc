#include "app/reports/calibration_plots.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <optional>
#include <sstream>

#include "estimator/models.h"

namespace irdist {
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
             SeriesColour(0) + "' notitle\n";
    }
    return "set xlabel 'calibration sample (index)'\nset ylabel 'dE_{rel} model error (%)'\n"
           "plot 0 notitle lc rgb '#000000', '__DATA__' using 0:5 with impulses lc rgb '" +
           SeriesColour(0) + "' notitle\n";
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
    << SeriesColour(1) << "' notitle\n"
    << tics.e_bottom << Fig7EPanels(e_problem, false) << tics.sigma_bottom
    << "set xlabel 'calibration sample (index)'\nset ylabel 'dSigma model error (%)'\n"
       "plot 0 notitle lc rgb '#000000', '__DATA__' using 0:6 with impulses lc rgb '"
    << SeriesColour(1) << "' notitle\nunset multiplot\n";
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
  s << "true d " << FixedDigits(p.d_mm, 0) << " mm, " << FixedDigits(p.theta_deg, 0) << " deg: ";
  const std::vector<double> roots = ZeroCrossings(p);
  if (roots.empty()) return s.str() + "no zero crossing";
  s << (roots.size() == 1 ? "crosses 0 at " : "crosses 0 at ");
  for (size_t i = 0; i < roots.size(); ++i) s << (i ? ", " : "") << FixedDigits(roots[i], 0);
  return s.str() + " mm";
}

std::optional<Plot> Fig8(const std::vector<CalibrationPoint>& points) {
  std::ostringstream data, s, plot;
  s << kPlotStyle << "set key below vertical Left reverse\n"
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
      << SeriesColour(block) << "' dt 2 lw 1.5\n";
    plot << (block ? ", " : "plot ") << "'__DATA__' index " << block
         << " using 1:2 with lines lw 1.5 lc rgb '" << SeriesColour(block) << "' title '"
         << CurveLabel(p) << "'";
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

}  // namespace irdist
