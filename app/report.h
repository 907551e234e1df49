#pragma once
// The run report: report/index.html, self-contained (SVG plots inlined, opens from disk), plots
// made by gnuplot. Each plot states its units and the paper's figure it reproduces.

#include <string>
#include <vector>

#include "app/summary.h"
#include "base/check.h"

namespace irdist {

class ReportError : public Error {
 public:
  using Error::Error;
};

// One plot: a gnuplot script body (after terminal and output are set) and its data file.
struct Plot {
  std::string name;     // file stem: <name>.dat, <name>.gp, <name>.svg
  std::string title;    // heading in the report
  std::string caption;  // what it shows, units, and which figure of the paper it reproduces
  std::string data;     // contents of <name>.dat (gnuplot blocks separated by two blank lines)
  std::string script;   // gnuplot commands; the data file is referred to as '<name>.dat'
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

std::vector<Plot> ValidationPlots(const std::vector<EstimateRow>& rows,
                                  const ValidationSummary& summary);
std::vector<Plot> CalibrationPlots(const std::vector<CalibrationPoint>& points);

// Writes <dir>/index.html and the plots' .dat/.gp/.svg beside it. `summary_text` is shown first
// (preformatted). When gnuplot is missing, the page says so and lists the data files instead.
// Returns the path of index.html. Throws ReportError when the folder cannot be written.
std::string WriteReport(const std::string& dir, const std::string& title,
                        const std::string& summary_text, const std::vector<Plot>& plots);

}  // namespace irdist
