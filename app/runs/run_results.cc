#include "app/runs/run_results.h"

#include <ostream>
#include <sstream>

#include "acquisition/recording_check.h"
#include "acquisition/recording_reader.h"
#include "app/inputs/errors.h"
#include "app/processing/bracket_estimates.h"
#include "app/processing/crb.h"
#include "app/processing/estimates_csv.h"
#include "app/processing/recording_fit.h"
#include "app/reports/calibration_report.h"
#include "app/reports/report.h"
#include "app/reports/summary.h"
#include "app/reports/validation_plots.h"
#include "estimator/model_file.h"

namespace irdist {

// A recording with errors (what `irdist check` reports) is refused before anything is computed
// from it: its first errors are listed with file:line.
void RequireCleanRecording(const std::string& dir, const std::string& refused) {
  const RecordingCheck check = CheckRecording(dir);
  if (check.ok()) return;
  std::ostringstream message;
  message << dir << ": the recording has " << check.errors.size() << " error(s); " << refused
          << ". First:";
  for (size_t i = 0; i < check.errors.size() && i < 5; ++i) {
    const RecordingCheck::Issue& issue = check.errors[i];
    message << "\n  " << issue.file << (issue.line > 0 ? ":" + std::to_string(issue.line) : "")
            << ": " << issue.message;
  }
  message << "\nRun `irdist check " << dir << "` for the full list, repair the recording (or "
          << "restore it from a copy) and try again.";
  throw CheckFailedError(message.str());
}

void WriteResults(const std::string& then, const std::function<void()>& write) {
  const auto refused = [&then](const Error& error) {
    return RunFolderError(std::string(error.what()) + "\nOnce that is fixed, " + then);
  };
  try {
    write();
  } catch (const ReportError& error) {
    throw refused(error);
  } catch (const EstimatesFileError& error) {
    throw refused(error);
  } catch (const ModelFileError& error) {
    throw refused(error);
  } catch (const RecordingError& error) {
    throw refused(error);
  }
}

ValidationSummary WriteValidation(const std::string& dir, const std::vector<EstimateRow>& rows,
                                  const std::map<std::string, std::string>& context,
                                  std::ostream& out) {
  WriteEstimatesCsv(dir + "/estimates.csv", rows);
  ValidationSummary summary = Summarize(rows);
  const std::map<std::string, CrbFigures> crb = ValidationCrb(context, summary);
  WriteSummaryYaml(dir + "/summary.yaml", summary, context, crb);
  const std::string index =
      WriteReport(dir + "/report", "irdist validation",
                  ValidationReportFields(context, summary, crb), summary.BriefReport(),
                  ValidationPlots(rows, summary));
  out << summary.BriefReport() << "\n";
  out << "Estimates: " << dir << "/estimates.csv\nSummary: " << dir
      << "/summary.yaml\nReport: " << index << "\n";
  return summary;
}

void ProcessRecordingOnly(const std::string& run_dir, const FeatureOptions& options,
                          const FeatureMap& cache, std::ostream& out) {
  RequireCleanRecording(run_dir + "/recording");
  const RecordingReader reader(run_dir + "/recording");
  const FeatureMap features = RecordingFeatures(reader, options, cache);
  WriteFeaturesCsv(run_dir + "/features.csv", reader.rows(), features);
  out << "Recorded " << reader.rows().size()
      << " frames (recipe: after: none); features: " << run_dir << "/features.csv\n";
}

void ProcessCalibration(const std::string& run_dir, const FeatureOptions& options,
                        const FeatureMap& cache, std::ostream& out, bool keep_model) {
  RequireCleanRecording(run_dir + "/recording");
  const RecordingReader reader(run_dir + "/recording");
  bool recovered = false;
  const FeatureOptions fit_options = FitFeatureOptions(reader, options, false, out, &recovered);
  // The live cache was computed without the curve: after a recovery every frame is recomputed.
  const FeatureMap features =
      RecordingFeatures(reader, fit_options, recovered ? FeatureMap{} : cache);
  WriteFeaturesCsv(run_dir + "/features.csv", reader.rows(), features);
  FitRecording(reader, features, fit_options, run_dir + "/model.yaml",
               CalibrationReportDrawerInto(run_dir + "/report", reader.dir()), out, keep_model);
}

void ProcessValidation(const std::string& run_dir, const CalibrationModel& model,
                       const std::map<std::string, std::string>& context, const FeatureMap& cache,
                       CommandIo io) {
  RequireCleanRecording(run_dir + "/recording");
  const RecordingReader reader(run_dir + "/recording");
  const FeatureMap features =
      RecordingFeatures(reader, model.features, cache, BlobFitModelOf(model));
  WriteFeaturesCsv(run_dir + "/features.csv", reader.rows(), features);
  const RecordingEstimates estimates = EstimateRecording(reader, features, model);
  for (const std::string& warning : estimates.warnings) io.err << warning << "\n";
  WriteValidation(run_dir, estimates.rows, context, io.out);
}

}  // namespace irdist
