#pragma once
// The last link of the chain: a run folder's results from its recording, the same for a live run
// after its sweep (calibrate, validate) and the offline commands (fit, playback):
// features.csv, then model.yaml + report/ (calibration) or estimates.csv + summary.yaml + report/
// (validation). A recording with errors is refused first.

#include <functional>
#include <iosfwd>
#include <map>
#include <string>
#include <vector>

#include "app/inputs/command_args.h"  // CommandIo
#include "app/processing/frame_features.h"
#include "app/processing/validation_summary.h"
#include "estimator/features.h"
#include "estimator/fit.h"

namespace irdist {

// A recording with errors (what `irdist check` reports) is refused before anything is computed
// from it: throws CheckFailedError listing its first errors with file:line, saying `refused`
// ("nothing is computed from it").
void RequireCleanRecording(const std::string& dir,
                           const std::string& refused = "nothing is computed from it");

// Runs `write`, which writes a folder's results. When a result cannot be written (a full disk, a
// folder not writable: ReportError, EstimatesFileError, ModelFileError, RecordingError), the error
// leaves as a RunFolderError with its message and "Once that is fixed, " + `then`: what to run
// then (a plain rerun would be refused by the results already there), e.g. "complete the
// results with: irdist playback REC --force".
void WriteResults(const std::string& then, const std::function<void()>& write);

// The processing after a live run, on DIR/recording: features.csv (frames in `cache` are taken
// from it), then model.yaml + report/ (calibration) or estimates.csv + summary.yaml + report/
// (validation, with `model`). A calibration whose recipe says `camera_response: recover` first
// recovers the response from the brackets and recomputes every frame's features with it (the
// cache, computed without it, is not used); the curve is stored in model.yaml.
void ProcessRecordingOnly(const std::string& run_dir, const FeatureOptions& options,
                          const FeatureMap& cache, std::ostream& out);  // features.csv only
// keep_model: model.yaml even when the fit fails its fitness (recording_fit.h FitRecording).
void ProcessCalibration(const std::string& run_dir, const FeatureOptions& options,
                        const FeatureMap& cache, std::ostream& out, bool keep_model = false);
// The recording's warnings (bracket_estimates.h EstimateRecording) go to io.err.
void ProcessValidation(const std::string& run_dir, const CalibrationModel& model,
                       const std::map<std::string, std::string>& context, const FeatureMap& cache,
                       CommandIo io);

// Writes estimates.csv, summary.yaml and report/ into `dir`; prints the summary's BriefReport.
ValidationSummary WriteValidation(const std::string& dir, const std::vector<EstimateRow>& rows,
                                  const std::map<std::string, std::string>& context,
                                  std::ostream& out);

}  // namespace irdist
