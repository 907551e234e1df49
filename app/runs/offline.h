#pragma once
// The offline commands (fit, playback, check) and the processing after recording, shared by the live runs (calibrate, validate) and the offline
// commands (fit, playback): per-frame features (features.csv), calibration samples and the fit,
// per-bracket estimates (estimates.csv, summary.yaml) and the reports. Live and offline call the
// same functions on the same rows, so the same recording (and model) gives byte-identical files.

#include <cstdint>
#include <iosfwd>
#include <map>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "app/cli/command_args.h"
#include "app/cli/errors.h"
#include "app/reports/report.h"
#include "app/reports/summary.h"
#include "estimator/estimate.h"
#include "estimator/features.h"
#include "estimator/fit.h"
#include "estimator/health.h"
#include "estimator/response.h"

namespace irdist {

// Forward declarations keep acquisition/recording.h out of the callers of this header.
class RecordingReader;
struct FrameRecord;

// Significant bits of a GenICam pixel format ("Mono12" -> 12); 16 when unknown.
int BitDepthOfPixelFormat(const std::string& pixel_format);

// Features of every row of a recording, by frame index.
using FeatureMap = std::map<std::int64_t, Features>;

// The features of one frame: the single function live and playback runs use. With a model
// (`blob_fit_model` non-null: the estimation default), the blob's moment variances are replaced by
// the likelihood fit with the calibrated blur (estimator/blob_fit.h, RefineWithBlobFit); without
// one (calibration, or the moments path chosen), they stay the intensity-weighted moments.
Features FrameFeatures(const cv::Mat& image, int bit_depth, const FeatureOptions& options,
                       const CalibrationModel* blob_fit_model = nullptr);

// The model FrameFeatures refines with (the blob fit): `model` unless its features.blob_fit is
// false (the moments path), then nullptr.
const CalibrationModel* BlobFitModelOf(const CalibrationModel& model);

// Features of every row of `reader` (rows() order). Rows whose index is in `cache` (frames still
// in memory from a live run, computed with the same model) are taken from it; the others are
// computed from their PNG.
FeatureMap RecordingFeatures(const RecordingReader& reader, const FeatureOptions& options,
                             const FeatureMap& cache = {},
                             const CalibrationModel* blob_fit_model = nullptr);

// features.csv: one row per frame of the recording, in rows() order (columns in docs/reports.md).
void WriteFeaturesCsv(const std::string& path, const std::vector<FrameRecord>& rows,
                      const FeatureMap& features);

// Every (reference, measurement) pair of the recording's complete brackets; a measurement pairs
// with the nearest reference before it in trigger order. Exposures are the requested ones.
std::vector<CalibrationSample> SamplesFromRecording(const RecordingReader& reader,
                                                    const FeatureMap& features);

// Calibration: samples -> Fit (default options) -> SaveModel(model_path) -> report in report_dir
// (measured vs modelled dE/dS, Eq. 25 curves). Prints each model's FitSummary to `out`.
CalibrationModel FitRecording(const RecordingReader& reader, const FeatureMap& features,
                              const FeatureOptions& feature_options, const std::string& model_path,
                              const std::string& report_dir, std::ostream& out);

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

// The report's calibration points (Fig. 7 and Fig. 8) for a fitted model.
std::vector<CalibrationPoint> CalibrationPointsOf(const CalibrationModel& model,
                                                  const std::vector<CalibrationSample>& samples,
                                                  int eq25_curves = 4);

// The estimate rows of one bracket, by method (estimates.csv lists the methods in this order).
struct BracketEstimateRows {
  std::vector<EstimateRow> i0_free, paper, i0_dependent, geometric;
  HealthCheck health;  // the default method's calibration health (estimator/health.h)
  MotionCheck motion;  // the default method's motion check (estimator/estimate.h)
};
// The rows of one complete bracket (none for an incomplete one): the single estimate path of
// validate, playback and measure, so the same frames give the same rows everywhere.
// With intrinsics in `geometry`, every ok row gets its 3D position (the mean blob centre of the
// measurement frames). Ground truth (distance, theta, x, y, z) is the camera-IRED geometry of the
// frames' recorded pose (app/processing/position.h TrueGeometryOf): the emitter's offsets on a virtual rig,
// a hardware rig's station.emitter_offset_mm.
struct RecordedBracket;
struct CameraGeometry;
BracketEstimateRows EstimateRecordedBracket(const RecordedBracket& bracket,
                                            const FeatureMap& features,
                                            const CalibrationModel& model,
                                            const CameraGeometry& geometry);
// The geometry of the rig a recording was made on (its header's rig text).
CameraGeometry GeometryOfRecording(const RecordingReader& reader);
// One bracket's rows in estimates.csv's order (the methods in the order above); estimates.csv
// lists bracket after bracket, so that measure can append each as it is made.
std::vector<EstimateRow> FlattenRows(const BracketEstimateRows& bracket);

// Model fitness: named warnings ("warning: model fitness (NAME): what; what to do") about a model
// before it is used: `blank_serial` (its provenance names no camera serial, so no camera can be
// checked against it), `no_provenance` (no provenance block: camera, ROI and bracket unknown),
// `no_fingerprint` (no calibrated blur: neither health nor the optics can be checked). Empty
// when none applies.
std::vector<std::string> ModelFitnessWarnings(const CalibrationModel& model,
                                              const std::string& model_path);
// The optics fingerprint (`optics_differ`): the blur measured on the first bracket whose health
// was assessed against the model's blur at that distance, with the model's blur at its
// calibrated distances in the message. "" when the first check is not flagged.
std::string OpticsFingerprintWarning(const CalibrationModel& model, const HealthCheck& first,
                                     double d_mm);

// The one warning of a run with moving brackets ("N of M brackets flagged moving: ... do").
std::string MotionWarning(int moving, int brackets);

// Estimates of every complete bracket: method "i0_free" (joint row dt_ms = 0, then one row per
// t_n) and "geometric" (the mean over the bracket's measurement frames, dt_ms = 0). Ground truth
// from the recording's rows (slide_mm, theta_deg, bias_ma_set).
std::vector<EstimateRow> EstimateRecording(const RecordingReader& reader,
                                           const FeatureMap& features,
                                           const CalibrationModel& model);

// The processing after a live run, on DIR/recording: features.csv (frames in `cache` are taken
// from it), then model.yaml + report/ (calibration) or estimates.csv + summary.yaml + report/
// (validation, with `model`). A calibration whose recipe says `camera_response: recover` first
// recovers the response from the brackets and recomputes every frame's features with it (the
// cache, computed without it, is not used); the curve is stored in model.yaml.
void ProcessRecordingOnly(const std::string& run_dir, const FeatureOptions& options,
                          const FeatureMap& cache, std::ostream& out);  // features.csv only
void ProcessCalibration(const std::string& run_dir, const FeatureOptions& options,
                        const FeatureMap& cache, std::ostream& out);
void ProcessValidation(const std::string& run_dir, const CalibrationModel& model,
                       const std::map<std::string, std::string>& context, const FeatureMap& cache,
                       std::ostream& out);

// Writes estimates.csv, summary.yaml and report/ into `dir`; prints the summary's BriefReport.
ValidationSummary WriteValidation(const std::string& dir, const std::vector<EstimateRow>& rows,
                                  const std::map<std::string, std::string>& context,
                                  std::ostream& out);

// The offline commands: `irdist fit`, `irdist playback`, `irdist check`. They throw
// RecordingError, ModelFileError, ...; RunCheck prints the check's report and throws
// CheckFailedError when the recording has errors.
void RunFit(const FitArgs& args, CommandIo io);
void RunPlayback(const PlaybackArgs& args, CommandIo io);
void RunCheck(const CheckArgs& args, CommandIo io);

}  // namespace irdist
