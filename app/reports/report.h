#pragma once
// The run report: report/index.html, self-contained (SVG plots inlined, opens from disk), plots
// made by gnuplot (run with an argument vector, never through a shell). A header table on top
// says which recipe, model, rig, software and date produced the page and gives the run's key
// figures. Each plot states its units and the paper's figure it reproduces; its title appears once
// (the page's heading), its legend sits outside the data.

#include <string>
#include <utility>
#include <vector>

#include "app/reports/summary.h"
#include "base/check.h"
#include "estimator/fit.h"

namespace irdist {

class ReportError : public Error {
 public:
  using Error::Error;
};

// One plot: a gnuplot script body (after terminal and output are set) and its data file.
struct Plot {
  std::string name;     // file stem: <name>.dat, <name>.gp, <name>.svg
  std::string title;    // heading in the report (the only place the title appears)
  std::string caption;  // what it shows, units, and which figure of the paper it reproduces
  std::string data;     // contents of <name>.dat (gnuplot blocks separated by two blank lines)
  std::string script;   // gnuplot commands; the data file is referred to as '__DATA__'
  int width_px = 900;   // SVG size
  int height_px = 500;
};

// One calibration sample as the report shows it (Fig. 7 and Fig. 8).
struct CalibrationPoint {
  double d_mm = 0.0;
  double theta_deg = 0.0;
  double bias_ma = 0.0;
  double dt_ms = 0.0;
  double de_measured = 0.0, de_model = 0.0;  // Delta E_rel and the I0-free model (Eq. 17)
  double ds_measured = 0.0, ds_model = 0.0;  // Delta Sigma and the I0-free model (Eq. 18)
  // Eq. 25 evaluated on a grid of distances (for a handful of samples; empty otherwise).
  std::vector<double> eq25_d_mm;
  std::vector<double> eq25_value;
};

// The page header: (label, value) rows in order.
using ReportFields = std::vector<std::pair<std::string, std::string>>;

std::vector<Plot> ValidationPlots(const std::vector<EstimateRow>& rows,
                                  const ValidationSummary& summary);
// `model` says whether the dE model (free_e) is a fit at all: a degenerate or ill-conditioned
// one is not drawn as a perfect fit.
std::vector<Plot> CalibrationPlots(const std::vector<CalibrationPoint>& points,
                                   const CalibrationModel& model);

// Why a fitted model's residuals do not measure its fit ("" when they do): degenerate (E
// proportional to F, or a rank-deficient Jacobian) or ill-conditioned.
std::string UnreliableFitReason(const FittedModel& model);

// recipe, rig, recording start and the software that recorded it, from a recording folder's
// recording.yaml (a row saying it could not be read otherwise).
ReportFields RecordingReportFields(const std::string& recording_dir);
// The calibration page's header: the recording's fields, the model file, each fit's status.
ReportFields CalibrationReportFields(const std::string& recording_dir,
                                     const std::string& model_path, const CalibrationModel& model);
// The validation page's header: `context` (recipe, model, recording), the recording's fields
// and each method's error figures, and each method's bound in `crb` (app/reports/crb.h
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
