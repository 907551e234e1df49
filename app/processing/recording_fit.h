#pragma once
// Calibration from a recording (calibrate after its sweep, and `irdist fit`): the complete
// brackets' differences as calibration samples, the camera response recovered when the recipe
// asks for it, the fit of every model the samples determine and model.yaml. The calibration
// report is drawn above this floor: the caller passes its drawer.

#include <functional>
#include <iosfwd>
#include <string>
#include <vector>

#include "app/processing/frame_features.h"
#include "estimator/features.h"
#include "base/check.h"
#include "estimator/fit.h"
#include "estimator/fitness.h"
#include "estimator/response.h"

namespace irdist {

class RecordingReader;

// Every (reference, measurement) pair of the recording's complete brackets; a measurement pairs
// with the nearest reference before it in trigger order. Exposures are the requested ones. With
// the rig's intrinsics each frame's features are those on its line of sight (position.h
// OnLineOfSight), as the estimates read them.
std::vector<CalibrationSample> SamplesFromRecording(const RecordingReader& reader,
                                                    const FeatureMap& features);

// A fit that failed its own fitness test (estimator/fitness.h) and was not kept: its model is
// written beside (RejectedModelPath) and the message names the worst poses, the probable cause
// and how to keep it. Exit code 1.
class FitnessError : public Error {
 public:
  using Error::Error;
};

// Where a model that failed its fitness and was not kept is written: "model.yaml" ->
// "model.rejected.yaml" (any other name: NAME.rejected.yaml).
std::string RejectedModelPath(const std::string& model_path);

// The pose of each bracket of the recording, in reader.Brackets() order (CalibrationSample::pose
// indexes it).
std::vector<FitnessPose> FitnessPosesOf(const RecordingReader& reader);

// Draws a calibration's report from the fitted model, the samples it was fitted on and the path
// its model file went to; returns the report's index page. Empty: no report (runs/ passes
// CalibrationReportDrawerInto, reports/calibration_report.h).
using CalibrationReportDrawer =
    std::function<std::string(const CalibrationModel& model,
                              const std::vector<CalibrationSample>& samples,
                              const std::string& model_path)>;

// Calibration: samples -> Fit (default options) -> the fit's fitness -> SaveModel(model_path) ->
// `draw_report` (measured vs modelled dE/dS, Eq. 25 curves). Prints each model's FitSummary and
// the fitness to `out`. A fit that fails its fitness warns; unless keep_model, its model goes to
// RejectedModelPath (the report drawn too) and FitnessError is thrown; a model written to
// model_path removes an earlier RejectedModelPath file (said in `out`).
CalibrationModel FitRecording(const RecordingReader& reader, const FeatureMap& features,
                              const FeatureOptions& feature_options, const std::string& model_path,
                              const CalibrationReportDrawer& draw_report, std::ostream& out,
                              bool keep_model = false);

// Whether a calibration of this recording recovers the camera response: its recipe's
// `calibration: {camera_response: recover}` (read from the recording's copy of the recipe).
bool RecipeAsksForResponse(const RecordingReader& reader);

// The camera's inverse response from the complete brackets of `reader` (each bracket one static
// stack at its frames' exposures; the neighbourhood is `options.window_side_px` around the blob).
// Prints the recovery's BriefReport and the curve to `out`. Throws ResponseError when the brackets
// cannot determine it (the message says how to fix the recipe).
ResponseRecovery RecoverRecordingResponse(const RecordingReader& reader,
                                          const FeatureOptions& options, std::ostream& out);

// `options` with the recovered curve applied to every pixel (ResponseScope::kAllPixels).
FeatureOptions WithResponse(const FeatureOptions& options, const ResponseRecovery& recovery);

// The features a fit of `reader` uses: `options`, or with the camera response recovered from
// the brackets when `force` or the recording's recipe asks for it (`*recovered` says which).
FeatureOptions FitFeatureOptions(const RecordingReader& reader, const FeatureOptions& options,
                                 bool force, std::ostream& out, bool* recovered = nullptr);

}  // namespace irdist
