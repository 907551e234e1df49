#pragma once
// The first link of the one chain from frames to distances (app/processing/): each frame's
// features, computed the same way live (measure, calibrate and validate as frames arrive) and
// offline (fit, playback), written to features.csv; and the differences of a bracket (each
// measurement frame with its reference), which the calibration samples and the estimates share.
// Live and offline call the same functions on the same rows, so the same recording (and model)
// gives byte-identical files.

#include <cstdint>
#include <map>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "base/check.h"
#include "estimator/features.h"
#include "estimator/fit.h"

namespace irdist {

// Forward declarations keep acquisition/recording_reader.h out of the callers of this header.
class RecordingReader;
struct FrameRecord;
struct RecordedBracket;

// Significant bits of a GenICam pixel format ("Mono12" -> 12); 16 when unknown.
int BitDepthOfPixelFormat(const std::string& pixel_format);

// A frame smaller than the features' window (FeatureOptions::window_side_px, a model's
// features.window_side_px): most often a model without provenance (its ROI never checked against
// the window) used on a smaller ROI. Its message names the key, the frame's size and the fix.
class FeatureWindowError : public Error {
 public:
  using Error::Error;
};

// Throws FeatureWindowError when `image` is narrower or lower than options.window_side_px.
void CheckFrameHoldsWindow(const cv::Mat& image, const FeatureOptions& options);

// Features of every row of a recording, by frame index.
using FeatureMap = std::map<std::int64_t, Features>;

// The features of one frame: the single function live and playback runs use. A frame smaller
// than the window is refused first (CheckFrameHoldsWindow). Then the scene
// pass (options.scene, estimator/scene.h CleanScene: defect pixels replaced, other blobs masked,
// occlusion and second sources named in Features::scene), then the features of the cleaned frame;
// with a model (`blob_fit_model` non-null: the estimation default), the blob's moment variances
// are replaced by the likelihood fit with the calibrated blur (estimator/blob_fit.h,
// RefineWithBlobFit) on the same cleaned frame; without one (calibration, or the moments path
// chosen), they stay the intensity-weighted moments. `scene`: a known defect map, the frame's ROI
// origin on the sensor, an expected blob centre (null: none).
// With the blob fit, each refined frame's own blur too (estimator/refocus.h MeasureOwnBlur), or,
// given `later`, what it needs kept there for a caller that answers first (measure --track):
// MeasurePendingOwnBlur then fills the features' own blur.
struct PendingOwnBlur {
  cv::Mat cleaned;                          // the scene-cleaned frame (shared, not copied)
  int bit_depth = 0;
  Features moments;                         // the features before the blob fit
  const CalibrationModel* model = nullptr;  // null: nothing pending
};
Features FrameFeatures(const cv::Mat& image, int bit_depth, const FeatureOptions& options,
                       const CalibrationModel* blob_fit_model = nullptr,
                       const SceneContext* scene = nullptr, PendingOwnBlur* later = nullptr);

// The own blur FrameFeatures left in `*pending` into `*features` (the same frame's); clears
// *pending. False when nothing was pending or the blur could not be measured.
bool MeasurePendingOwnBlur(PendingOwnBlur* pending, Features* features);

// The frame every feature and the blob fit read (the scene pass of FrameFeatures): for the
// callers that hand a recorded frame to the blob fit or the blur split themselves
// (app/processing/recording_fit.cc), so they see what FrameFeatures saw.
cv::Mat SceneCleanedFrame(const cv::Mat& image, int bit_depth, const FeatureOptions& options,
                          const SceneContext* scene = nullptr);

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

// A number as features.csv writes it: %.10g, "nan" when not finite.
std::string FeatureNumber(double value);

// The features of `row` in `features`; a missing frame is a bug (IRDIST_CHECK).
const Features& FeaturesOf(const FeatureMap& features, const FrameRecord& row);

// A measurement frame of a bracket with the reference it is differenced with.
struct DifferencePair {
  const FrameRecord* reference = nullptr;
  const FrameRecord* measurement = nullptr;
};
// The differences of a bracket: each measurement pairs with the nearest reference before it in
// trigger order (interleaved brackets); a measurement before any reference is left out.
std::vector<DifferencePair> DifferencePairsOf(const RecordedBracket& bracket);

}  // namespace irdist
