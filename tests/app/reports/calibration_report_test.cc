// The calibration's page (app/reports/calibration_report.h): the drawer FitRecording is given
// writes report/index.html naming the recording and the model file it drew, and a model without
// the I0-free models has no points to draw.
#include "app/reports/calibration_report.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>
#include <vector>

#include "tests/app/reports/report_helpers.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;
using testing::Slurp;

TEST(CalibrationReport, DrawerWritesThePageNamingTheRecordingAndTheModel) {
  const fs::path dir =
      fs::temp_directory_path() / ("irdist_calreport_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const CalibrationReportDrawer draw =
      CalibrationReportDrawerInto((dir / "report").string(), "/recordings/bench-7");
  ASSERT_TRUE(draw);
  const std::string index = draw(CalibrationModel{}, {}, "/runs/bench-7/model.rejected.yaml");
  EXPECT_EQ(index, (dir / "report" / "index.html").string());
  const std::string html = Slurp(index);
  EXPECT_NE(html.find("Calibration from /recordings/bench-7"), std::string::npos) << html;
  EXPECT_NE(html.find("/runs/bench-7/model.rejected.yaml"), std::string::npos) << html;
  fs::remove_all(dir);
}

TEST(CalibrationReport, NoPointsWithoutTheI0FreeModels) {
  CalibrationSample sample;
  sample.d_mm = 2000.0;
  sample.reference.blob_found = sample.measurement.blob_found = true;
  CalibrationModel model;  // no free_e / free_sigma fitted
  EXPECT_TRUE(CalibrationPointsOf(model, {sample}).empty());
  FittedModel free_e;
  free_e.kind = ModelKind::kFreeE;
  model.models.push_back(free_e);  // free_sigma still missing
  EXPECT_TRUE(CalibrationPointsOf(model, {sample}).empty());
}

}  // namespace
}  // namespace irdist
