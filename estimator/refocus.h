#pragma once
// A focus change measured through: each frame's blob fit finds its OWN blur
// (the blur variance its one-pass cost is lowest at, the same cost and blob family the
// calibration fitted its blob-fit blur with: blob_fit.h FitBlurSplit), and the disc's size at that
// blur. A bracket's blur is the joint minimum of its measurement frames' costs; where it departs
// from the calibrated blob-fit blur beyond its noise (estimator/health.h, the blob-fit figure),
// the bracket is estimated with its own blur (app/processing/bracket_estimates.cc: `refocused`).
// docs/estimator.md, "A focus change measured through".

#include <opencv2/core.hpp>
#include <vector>

#include "estimator/blob_fit.h"
#include "estimator/features.h"
#include "estimator/fit.h"

namespace irdist {

// MeasureOwnBlur's search, relative to the calibrated blur the frame was fitted with: a focus
// change from 0.4x to 3x the calibrated blur variance (about -50% to +70% of its sigma).
constexpr double kOwnBlurLowFactor = 0.4;
constexpr double kOwnBlurHighFactor = 3.0;

// Newton's method on the blob fit's one-pass cost over the blur variance (ProfileBlobBlur: one
// one-pass fit and one model evaluation a step) from *blur, each step clamped to a quarter of the
// blur and to [low, high], the last one below 2% of it; the minimum into *blur and the last
// profile (one short step from it: its standard error and slopes) into *at. False when a profile
// fails (a fit fails, or the cost is not convex where the search stands) or the minimum lies on
// the search's edge or beyond it.
bool NewtonOnBlobBlur(const cv::Mat& image, int bit_depth, const Features& start,
                      const Crosstalk& crosstalk, double low, double high, double* blur,
                      BlobBlurProfile* at);

// The frame's own blur into `out`'s own_* fields (features.h): Newton's method on the blob fit's
// one-pass cost over the blur variance (FitBlobPasses, the model's crosstalk), from the
// calibrated blur, each step the blur's profile (blob_fit.h ProfileBlobBlur: the fit's
// Gauss-Newton system with the blur as an eighth parameter); its standard error from the cost's
// curvature there (scaled by the cost per pixel: the read noise's weights understate a
// shot-noise-limited frame's noise), and the disc's variances at that blur with their slopes in
// the blur, the fit re-solved (near the calibrated blur, within 5%: the refined disc moved
// along them; beyond, FitBlob at the blur). One profile in the usual case (a fit and one model
// evaluation), a few after a focus change. `start`: the frame's features before
// RefineWithBlobFit (the calibration's blur split started from the same); `out`: the refined
// features (size_blur_var_px2 the calibrated blur used). Returns false (the fields left NaN)
// without a refined blob, when a fit fails, where the cost is not convex, or when the minimum
// lies on the search's edge (a blur the search cannot bracket).
bool MeasureOwnBlur(const cv::Mat& image, int bit_depth, const CalibrationModel& model,
                    const Features& start, Features* out);

// A bracket's blob-fit blur: the joint minimum of its frames' costs, each represented by its
// minimum and curvature (own_blur_var_px2, own_blur_se_px2): their inverse-variance mean. The
// standard error grows by sqrt(chi2 / dof) where the frames disagree beyond their errors. The
// calibrated blur the same way (each frame's size_blur_var_px2).
struct BracketBlur {
  int frames = 0;                      // frames with an own blur (0: not measured)
  double blur_var_px2 = 0.0;           // the bracket's own blur variance, px^2
  double se_px2 = 0.0;                 // its standard error
  double calibrated_px2 = 0.0;         // the calibrated blob-fit blur at the frames' distances
  double chi2_per_dof = 0.0;           // the frames' scatter about their mean (1 frame: 0)
};
BracketBlur FitBracketBlur(const std::vector<const Features*>& frames);

// The frame's features with its blob's size at blur `blur_var_px2` instead of the calibrated
// blur: the disc's variances at its own blur moved along their slopes to that blur, plus the
// calibrated blur (size_blur_var_px2) that the geometric model's sizes carry. Unchanged when the
// frame has no own blur.
Features AtBlur(const Features& f, double blur_var_px2);

}  // namespace irdist
