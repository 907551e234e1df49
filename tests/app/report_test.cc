#include "app/report.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

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
  const std::string index = WriteReport(dir.string(), "Validation", summary.BriefReport(), plots);
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
  }
  EXPECT_EQ(html.find("not drawn"), std::string::npos) << "a plot failed; see the .log files in "
                                                       << dir;
  // Self-contained: the SVGs are inline, no external references.
  EXPECT_NE(html.find("<svg"), std::string::npos);
  EXPECT_EQ(html.find("src="), std::string::npos);
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
  const auto plots = CalibrationPlots(points);
  ASSERT_EQ(plots.size(), 2u);
  const fs::path dir = fs::temp_directory_path() / ("irdist_calrep_" + std::to_string(::getpid()));
  const std::string html = Slurp(WriteReport(dir.string(), "Calibration", "fit", plots));
  EXPECT_EQ(html.find("not drawn"), std::string::npos);
  EXPECT_TRUE(fs::exists(dir / "fig7_fit.svg"));
  EXPECT_TRUE(fs::exists(dir / "fig8_eq25.svg"));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace irdist
