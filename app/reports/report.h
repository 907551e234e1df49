#pragma once
// Where a report is drawn: the run report, report/index.html, self-contained (SVG plots inlined,
// opens from disk), plots made by gnuplot (run with an argument vector, never through a shell)
// from the figures of app/reports/validation_plots.h and calibration_plots.h. A header table on top
// says which recipe, model, rig, software and date produced the page and gives the run's key
// figures. Each plot states its units and the paper's figure it reproduces; its title appears once
// (the page's heading), its legend sits outside the data.

#include <string>
#include <utility>
#include <vector>

#include "app/processing/validation_summary.h"
#include "app/reports/plot.h"
#include "base/check.h"
#include "estimator/fit.h"

namespace irdist {

class ReportError : public Error {
 public:
  using Error::Error;
};

// The page header: (label, value) rows in order.
using ReportFields = std::vector<std::pair<std::string, std::string>>;

// recipe, rig, recording start and the software that recorded it, from a recording folder's
// recording.yaml (a row saying it could not be read otherwise).
ReportFields RecordingReportFields(const std::string& recording_dir);
// The calibration page's header: the recording's fields, the model file, each fit's status.
ReportFields CalibrationReportFields(const std::string& recording_dir,
                                     const std::string& model_path, const CalibrationModel& model);
// The validation page's header: `context` (recipe, model, recording), the recording's fields
// and each method's error figures, and each method's bound in `crb` (app/processing/crb.h
// ValidationCrb).
ReportFields ValidationReportFields(const std::map<std::string, std::string>& context,
                                    const ValidationSummary& summary,
                                    const std::map<std::string, CrbFigures>& crb = {});

// Writes <dir>/index.html and the plots' .dat/.gp/.svg/.log beside it. The header table holds
// `fields` then the report's date and irdist version; `summary_text` follows (preformatted).
// When gnuplot is missing or fails, the page says so for each plot. Returns the path of
// index.html. Throws ReportError when the folder cannot be written.
std::string WriteReport(const std::string& dir, const std::string& title,
                        const ReportFields& fields, const std::string& summary_text,
                        const std::vector<Plot>& plots);

}  // namespace irdist
