#pragma once
// Where a frame becomes a distance: the estimates of one recorded bracket by every method (the
// default I0-free estimator, the paper's Algorithm 1, the I0-dependent and geometric baselines),
// with the calibration's health, the motion check and the 3D position; one path for validate,
// playback and, live, measure. And the warnings about a model before it is used.

#include <string>
#include <vector>

#include "app/processing/estimates_csv.h"
#include "app/processing/frame_features.h"
#include "estimator/bracket_checks.h"
#include "estimator/estimate.h"
#include "estimator/fit.h"
#include "estimator/health.h"

namespace irdist {

class RecordingReader;
struct RecordedBracket;
struct CameraGeometry;

// The estimate rows of one bracket, by method (estimates.csv lists the methods in this order).
struct BracketEstimateRows {
  std::vector<EstimateRow> i0_free, paper, i0_dependent, geometric;
  HealthCheck health;  // the default method's calibration health (estimator/health.h)
  MotionCheck motion;  // the default method's motion check (estimator/bracket_checks.h)
};
// The rows of one complete bracket (none for an incomplete one): the single estimate path of
// validate, playback and measure, so the same frames give the same rows everywhere.
// With intrinsics in `geometry`, every ok row gets its 3D position (the mean blob centre of the
// measurement frames). Ground truth (distance, theta, x, y, z) is the camera-IRED geometry of the
// frames' recorded pose (app/processing/position.h TrueGeometryOf): the emitter's offsets on a
// virtual rig, a hardware rig's station.emitter_offset_mm.
BracketEstimateRows EstimateRecordedBracket(const RecordedBracket& bracket,
                                            const FeatureMap& features,
                                            const CalibrationModel& model,
                                            const CameraGeometry& geometry);
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
// from the recording's rows (slide_mm, theta_deg, bias_ma_set). The recording's warnings, each
// once (other optics than the model's, the calibration's health, brackets taken while moving),
// as lines for the caller's diagnostics stream.
struct RecordingEstimates {
  std::vector<EstimateRow> rows;
  std::vector<std::string> warnings;
};
RecordingEstimates EstimateRecording(const RecordingReader& reader, const FeatureMap& features,
                                     const CalibrationModel& model);

}  // namespace irdist
