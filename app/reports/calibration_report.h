#pragma once
// The calibration's page, report/index.html: the samples as the report shows them (Fig. 7's
// measured against modelled differences, Fig. 8's Eq. 25 curves), the page drawn with the fit's
// status in its header (app/reports/report.h), and the drawer app/processing/recording_fit.h's
// FitRecording calls once the model is written.

#include <string>
#include <vector>

#include "app/processing/recording_fit.h"
#include "app/reports/calibration_plots.h"
#include "estimator/fit.h"

namespace irdist {

// The report's calibration points (Fig. 7 and Fig. 8) for a fitted model: one per sample with
// both frames usable, Eq. 25 drawn for `eq25_curves` of them spread over the samples. Empty when
// the model has no I0-free models.
std::vector<CalibrationPoint> CalibrationPointsOf(const CalibrationModel& model,
                                                  const std::vector<CalibrationSample>& samples,
                                                  int eq25_curves = 4);

// Draws the calibration of the recording in `recording_dir` into `report_dir` (its model file at
// `model_path`); returns the path of index.html. Throws ReportError.
std::string WriteCalibrationReport(const std::string& recording_dir,
                                   const std::vector<CalibrationSample>& samples,
                                   const CalibrationModel& model, const std::string& model_path,
                                   const std::string& report_dir);

// The drawer FitRecording takes: WriteCalibrationReport into `report_dir`.
CalibrationReportDrawer CalibrationReportDrawerInto(const std::string& report_dir,
                                                    const std::string& recording_dir);

}  // namespace irdist
