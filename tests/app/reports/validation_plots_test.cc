// The validation figures: Fig. 10's residual panels, the methods plot, the ticks of Fig. 14.
#include "app/reports/validation_plots.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "tests/app/reports/report_helpers.h"

namespace irdist {
namespace {

using testing::Named;
using testing::Rows;
using testing::TickSteps;

TEST(ValidationPlots, Fig10HasAResidualPanelPerCurrentAndMethodsKeepTheTrueDistance) {
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

// Readable at 1280 px: 110 repetitions get at most about 10 x labels on Fig. 14 (each was
// labelled).
TEST(ValidationPlots, Fig14TicksAreChosenForTheDataAtMostAboutTenLabels) {
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
}

}  // namespace
}  // namespace irdist
