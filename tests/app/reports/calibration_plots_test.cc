// The calibration figures: Fig. 7 and the Eq. 25 curves of Fig. 8, a degenerate E model not drawn
// as a perfect fit, each Fig. 7 panel's ticks chosen for its data.
#include "app/reports/calibration_plots.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "app/reports/report.h"
#include "tests/app/reports/report_helpers.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;
using testing::Named;
using testing::Slurp;
using testing::TickSteps;

TEST(CalibrationPlots, CalibrationReportShowsFitAndEq25) {
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

TEST(CalibrationPlots, DegenerateEModelIsNotDrawnAsAPerfectFit) {
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

// Readable at 1280 px: each Fig. 7 panel's ticks are chosen for its data.
TEST(CalibrationPlots, Fig7TicksAreChosenForTheDataAtMostAboutTenLabels) {
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
