#include "app/reports/report.h"

#include <gtest/gtest.h>
#include <sys/resource.h>

#include <csignal>

#include <cctype>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace irdist {
namespace {

namespace fs = std::filesystem;

std::vector<EstimateRow> Rows() {
  std::vector<EstimateRow> rows;
  int bracket = 0;
  for (double d : {1500.0, 2000.0, 2500.0}) {
    for (double ma : {475.0, 525.0}) {
      for (int rep = 0; rep < 3; ++rep) {
        for (double dt : {0.0, 22.0, 24.0}) {
          EstimateRow r;
          r.bracket = bracket;
          r.repeat = rep;
          r.method = "i0_free";
          r.dt_ms = dt;
          r.true_d_mm = d;
          r.true_theta_deg = 20.0;
          r.bias_ma = ma;
          r.d_mm = d * (1.0 + 0.001 * (rep - 1) + 0.0001 * dt);
          r.theta_deg = 20.5;
          rows.push_back(r);
        }
        EstimateRow g = rows.back();
        g.method = "geometric";
        g.dt_ms = 0.0;
        g.d_mm = d * 1.004;
        rows.push_back(g);
        ++bracket;
      }
    }
  }
  return rows;
}

std::string Slurp(const fs::path& p) {
  std::ifstream in(p);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(Report, ValidationReportHasEveryFigureDrawnAndCaptioned) {
  const auto rows = Rows();
  const auto summary = Summarize(rows);
  const auto plots = ValidationPlots(rows, summary);
  std::vector<std::string> names;
  for (const Plot& p : plots) names.push_back(p.name);
  // Repeats >= 3 give Fig. 14; two methods give the comparison; two dts give Fig. 11.
  EXPECT_EQ(names, (std::vector<std::string>{"fig10_distance", "fig11_dt", "fig13_scatter",
                                             "fig13_histogram", "fig14_repetitions", "methods"}));
  const fs::path dir = fs::temp_directory_path() / ("irdist_report_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const std::string index = WriteReport(dir.string(), "Validation", {{"recipe", "recipes/v.yaml"}},
                                        summary.BriefReport(), plots);
  const std::string html = Slurp(index);
  for (const Plot& p : plots) {
    EXPECT_TRUE(fs::exists(dir / (p.name + ".svg"))) << p.name;
    EXPECT_NE(html.find("id='" + p.name + "'"), std::string::npos) << p.name;
    EXPECT_TRUE(p.caption.find("Fig.") != std::string::npos ||
                p.caption.find("Not a figure of the paper") != std::string::npos)
        << p.name << ": the caption must say which figure it reproduces";
    EXPECT_TRUE(p.caption.find("(mm)") != std::string::npos ||
                p.caption.find("(%)") != std::string::npos)
        << p.name << ": the caption gives no unit";
    EXPECT_EQ(p.caption.find("NOTES.md"), std::string::npos) << p.name;
    EXPECT_EQ(p.caption.find("irdist show"), std::string::npos) << p.name;
    // The title is the page's heading only, not repeated inside the plot.
    EXPECT_EQ(Slurp(dir / (p.name + ".svg")).find(p.title), std::string::npos) << p.name;
    EXPECT_TRUE(p.script.find("key outside") != std::string::npos ||
                p.script.find("title '") == std::string::npos)
        << p.name << ": a legend on the data";
  }
  // The header says what produced the page.
  EXPECT_NE(html.find("<th>recipe</th><td>recipes/v.yaml</td>"), std::string::npos);
  EXPECT_NE(html.find("<th>report written</th>"), std::string::npos);
  EXPECT_EQ(html.find("class='missing'"), std::string::npos)
      << "a plot failed; see the .log files in " << dir;
  // Self-contained: the SVGs are inline, no external references.
  EXPECT_NE(html.find("<svg"), std::string::npos);
  EXPECT_EQ(html.find("src="), std::string::npos);
  fs::remove_all(dir);
}

const Plot& Named(const std::vector<Plot>& plots, const std::string& name) {
  for (const Plot& p : plots) {
    if (p.name == name) return p;
  }
  throw std::runtime_error("no plot " + name);
}

TEST(Report, Fig10HasAResidualPanelPerCurrentAndMethodsKeepTheTrueDistance) {
  const auto rows = Rows();
  const auto plots = ValidationPlots(rows, Summarize(rows));
  const Plot& fig10 = Named(plots, "fig10_distance");
  EXPECT_NE(fig10.script.find("estimate - truth (mm)"), std::string::npos);
  EXPECT_NE(fig10.script.find("title 'mean, 475 mA'"), std::string::npos);
  EXPECT_NE(fig10.script.find("title 'mean, 525 mA'"), std::string::npos);
  // Residual column: estimate - truth of the first row (1500 mm, rep 0: -0.1%).
  EXPECT_NE(fig10.data.find("1500 1498.5 -1.5"), std::string::npos) << fig10.data;
  const Plot& methods = Named(plots, "methods");
  EXPECT_EQ(methods.script.find("$1+"), std::string::npos) << "methods offset along d";
  EXPECT_NE(methods.script.find("multiplot layout 2,1"), std::string::npos);
  EXPECT_EQ(methods.data.substr(0, 5), "1500 ");
}

TEST(Report, HostilePathsRunNoShellAndEveryPlotIsDrawn) {
  const auto rows = Rows();
  const auto summary = Summarize(rows);
  const auto plots = ValidationPlots(rows, summary);
  const fs::path root =
      fs::temp_directory_path() / ("irdist_hostile_" + std::to_string(::getpid()));
  fs::remove_all(root);
  fs::create_directories(root);
  const fs::path cwd = fs::current_path();
  fs::current_path(root);
  for (const std::string name :
       {"x'; touch INJECTED; echo '", "lab's run", "a \"b\" $HOME ; c", "$(touch INJECTED)"}) {
    const fs::path dir = root / name / "report";
    const std::string html = Slurp(WriteReport(dir.string(), "V", {}, "s", plots));
    EXPECT_EQ(html.find("class='missing'"), std::string::npos) << name;
    for (const Plot& p : plots) EXPECT_TRUE(fs::exists(dir / (p.name + ".svg"))) << name;
  }
  fs::current_path(cwd);
  for (const auto& entry : fs::recursive_directory_iterator(root)) {
    EXPECT_NE(entry.path().filename(), "INJECTED") << entry.path();
  }
  EXPECT_FALSE(fs::exists(cwd / "INJECTED"));
  fs::remove_all(root);
}

// A disk that fills up while the report is written, simulated with a file size limit (writes
// past it fail as on a full disk; gnuplot inherits the limit and cuts its SVG short).
class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) {
    ::getrlimit(RLIMIT_FSIZE, &saved_);
    old_handler_ = std::signal(SIGXFSZ, SIG_IGN);
    rlimit limit = saved_;
    limit.rlim_cur = bytes;
    ::setrlimit(RLIMIT_FSIZE, &limit);
  }
  ~FileSizeLimit() {
    ::setrlimit(RLIMIT_FSIZE, &saved_);
    std::signal(SIGXFSZ, old_handler_);
  }
  FileSizeLimit(const FileSizeLimit&) = delete;
  FileSizeLimit& operator=(const FileSizeLimit&) = delete;

 private:
  rlimit saved_{};
  void (*old_handler_)(int) = nullptr;
};

// A full disk never leaves a cut report that looks whole: the error names the file and the fix,
// and no page (nor its temporary file) is left behind.
TEST(Report, AFullDiskIsAnErrorWithTheFixNotACutReport) {
  const fs::path dir = fs::temp_directory_path() / ("irdist_full_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const auto rows = Rows();
  const auto plots = ValidationPlots(rows, Summarize(rows));
  for (const bool with_plots : {true, false}) {
    SCOPED_TRACE(with_plots ? "a plot cut short" : "the page cut short");
    fs::remove_all(dir);
    try {
      FileSizeLimit limit(6000);  // each .dat and .gp fits; an SVG or the page does not
      WriteReport(dir.string(), "V", {}, std::string(with_plots ? 10 : 20000, 's'),
                  with_plots ? plots : std::vector<Plot>{});
      ADD_FAILURE() << "the report was written whole under a 6000-byte limit";
    } catch (const ReportError& e) {
      EXPECT_NE(std::string(e.what()).find("free disk space (df -h " + dir.string() + ")"),
                std::string::npos)
          << e.what();
    }
    EXPECT_FALSE(fs::exists(dir / "index.html"));
    EXPECT_FALSE(fs::exists(dir / "index.html.tmp"));
  }
  fs::remove_all(dir);
}

TEST(Report, CalibrationReportShowsFitAndEq25) {
  std::vector<CalibrationPoint> points;
  for (int i = 0; i < 10; ++i) {
    CalibrationPoint p;
    p.d_mm = 1500 + 100 * i;
    p.de_measured = 0.01 * (i + 1);
    p.de_model = p.de_measured * 1.002;
    p.ds_measured = 3.0 * (i + 1);
    p.ds_model = p.ds_measured * 0.997;
    for (double d = 1000; d <= 3500; d += 100) {
      p.eq25_d_mm.push_back(d);
      p.eq25_value.push_back(d - p.d_mm);
    }
    points.push_back(p);
  }
  CalibrationModel model;
  FittedModel free_e;
  free_e.kind = ModelKind::kFreeE;
  free_e.summary.termination = FitSummary::Termination::kConverged;
  model.models.push_back(free_e);
  const auto plots = CalibrationPlots(points, model);
  ASSERT_EQ(plots.size(), 2u);
  EXPECT_NE(plots[0].script.find("dE_{rel} model error (%)"), std::string::npos);
  // Fig. 8 marks each curve's true distance and says where it crosses zero (here: at the truth).
  EXPECT_NE(plots[1].script.find("set arrow from 1500, graph 0"), std::string::npos);
  EXPECT_NE(plots[1].script.find("true d 1500 mm, 0 deg: crosses 0 at 1500 mm"), std::string::npos)
      << plots[1].script;
  const fs::path dir = fs::temp_directory_path() / ("irdist_calrep_" + std::to_string(::getpid()));
  const std::string html = Slurp(WriteReport(dir.string(), "Calibration", {}, "fit", plots));
  EXPECT_EQ(html.find("class='missing'"), std::string::npos);
  EXPECT_TRUE(fs::exists(dir / "fig7_fit.svg"));
  EXPECT_TRUE(fs::exists(dir / "fig8_eq25.svg"));
  fs::remove_all(dir);
}

TEST(Report, DegenerateEModelIsNotDrawnAsAPerfectFit) {
  std::vector<CalibrationPoint> points(5);
  for (int i = 0; i < 5; ++i) {
    points[i].d_mm = 1500 + 250 * i;
    points[i].de_measured = points[i].de_model = 0.1 * (i + 1);  // "perfect"
    points[i].ds_measured = 1.0 + i;
    points[i].ds_model = 1.01 * (1.0 + i);
  }
  CalibrationModel model;
  FittedModel free_e;
  free_e.kind = ModelKind::kFreeE;
  free_e.summary.termination = FitSummary::Termination::kDegenerate;
  free_e.summary.message = "rank 16 of 17; null directions: [0.7 q3 - 0.7 q5]";
  model.models.push_back(free_e);
  EXPECT_NE(UnreliableFitReason(free_e).find("degenerate"), std::string::npos);
  const auto plots = CalibrationPlots(points, model);
  ASSERT_FALSE(plots.empty());
  EXPECT_EQ(plots[0].script.find("dE_{rel} model error"), std::string::npos);
  EXPECT_EQ(plots[0].script.find("'model dE_{rel}'"), std::string::npos);
  EXPECT_NE(plots[0].script.find("not a fit"), std::string::npos);
  EXPECT_NE(plots[0].caption.find("degenerate"), std::string::npos);
  const fs::path dir = fs::temp_directory_path() / ("irdist_degrep_" + std::to_string(::getpid()));
  const std::string html = Slurp(WriteReport(dir.string(), "Calibration", {}, "fit", plots));
  EXPECT_EQ(html.find("class='missing'"), std::string::npos);
  fs::remove_all(dir);
}

// The steps of "set xtics STEP" / "set ytics STEP" (or "set xtics START, STEP") in a script.
std::vector<double> TickSteps(const std::string& script, const std::string& axis) {
  std::vector<double> steps;
  const std::string key = "set " + axis + "tics ";
  for (size_t at = script.find(key); at != std::string::npos; at = script.find(key, at + 1)) {
    const size_t from = at + key.size();
    const std::string line = script.substr(from, script.find('\n', at) - from);
    if (line.empty() || !(std::isdigit(line[0]) || line[0] == '.')) continue;
    const size_t comma = line.find(',');
    steps.push_back(std::stod(comma == std::string::npos ? line : line.substr(comma + 1)));
  }
  return steps;
}

// Readable at 1280 px: 110 repetitions get at most about 10 x labels on Fig. 14 (each was
// labelled), and each Fig. 7 panel's ticks are chosen for its data.
TEST(Report, TicksAreChosenForTheDataAtMostAboutTenLabels) {
  std::vector<EstimateRow> rows;
  for (int rep = 0; rep < 110; ++rep) {
    for (double d : {1500.0, 2500.0}) {
      EstimateRow r;
      r.bracket = static_cast<int>(rows.size());
      r.repeat = rep;
      r.method = "i0_free";
      r.true_d_mm = d;
      r.d_mm = d + 0.01 * rep;
      rows.push_back(r);
    }
  }
  const std::vector<Plot> validation_plots = ValidationPlots(rows, Summarize(rows));
  const Plot& fig14 = Named(validation_plots, "fig14_repetitions");
  const std::vector<double> x14 = TickSteps(fig14.script, "x");
  ASSERT_EQ(x14.size(), 1u) << fig14.script;
  EXPECT_GE(x14[0], 1.0);
  EXPECT_LE(109.0 / x14[0], 10.0) << fig14.script;

  std::vector<CalibrationPoint> points(256);
  for (size_t i = 0; i < points.size(); ++i) {
    points[i].d_mm = 1500.0 + 500.0 * static_cast<double>(i % 4);
    points[i].de_measured = 0.005 + 0.0002 * static_cast<double>(i);
    points[i].de_model = points[i].de_measured * 1.001;
    points[i].ds_measured = 0.02 + 0.0005 * static_cast<double>(i);
    points[i].ds_model = points[i].ds_measured * 0.999;
  }
  CalibrationModel model;
  FittedModel free_e;
  free_e.kind = ModelKind::kFreeE;
  free_e.summary.termination = FitSummary::Termination::kConverged;
  model.models.push_back(free_e);
  const std::vector<Plot> calibration_plots = CalibrationPlots(points, model);
  const Plot& fig7 = Named(calibration_plots, "fig7_fit");
  // Four panels, each with its x and y step; the sample index (0..255) at most ~10 labels.
  const std::vector<double> x7 = TickSteps(fig7.script, "x"), y7 = TickSteps(fig7.script, "y");
  ASSERT_EQ(x7.size(), 4u) << fig7.script;
  ASSERT_EQ(y7.size(), 4u) << fig7.script;
  EXPECT_LE(255.0 / x7[2], 10.0) << fig7.script;  // the bottom panels: the sample index
  EXPECT_LE(255.0 / x7[3], 10.0) << fig7.script;
  const double de_span = points.back().de_model - points.front().de_measured;
  EXPECT_LE(de_span / x7[0], 10.0) << fig7.script;
  EXPECT_LE(de_span / y7[0], 10.0) << fig7.script;
}

}  // namespace
}  // namespace irdist
