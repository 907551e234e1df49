#pragma once
// The camera's inverse radiometric response f recovered from frames of a static scene taken at
// several known exposures (our brackets: the reference t_r and the measurements t_n of one pose at
// one current). Method (docs/estimator.md, "Camera response"):
//  - f is piecewise linear on num_knots knots spread evenly over the normalised gray level [0,1].
//  - For every pixel of the blob's neighbourhood and every pair of exposures (t_a < t_b) of a
//    stack, the linear signal is proportional to the exposure: f(M_a) / t_a - f(M_b) / t_b = 0, one
//    homogeneous linear equation in the knot values. The black level then comes out of the data
//    (f(M_black) = 0) and no dark frame is needed.
//  - Samples with a gray level at or above saturation_fraction of full scale, or whose shorter
//    exposure is within min_signal_fraction of the stack's background, are left out.
//  - The equations of group_size pixels are summed (f enters linearly, so a sum is still one
//    linear equation); the groups are formed by sorting the pixels by their rate M / t in the
//    stack's other frames, which carry none of the pair's noise. Per-pixel rows would be biased:
//    the noise in M_a and M_b sits in the rows' coefficients (errors in variables) and flattens f
//    where the scene's gray levels cluster (1.4 % on a linear camera, 0.05 % grouped).
//  - Rows weighted by 1 / sqrt(M_a / t_a^2 + M_b / t_b^2) (shot-noise-like variance of the row),
//    a second-difference penalty on the knots (the curve continues straight where no data reach),
//    f(1) = 1, solved by linear least squares (Eigen, the normal equations of the stacked rows),
//    then checked for monotonicity.
// Each stack must be static: the same pose, current and scene in every frame.

#include <cstdint>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "base/check.h"
#include "estimator/features.h"

namespace irdist {

// The brackets cannot determine the response (too few gray levels, exposures or samples; a
// non-monotone solution). what() says what was found and how to fix it.
class ResponseError : public Error {
 public:
  using Error::Error;
};

struct ResponseOptions {
  // Knots of the piecewise-linear f, evenly spaced on [0,1] (first at 0, last at 1).
  int num_knots = 17;
  // Weight of the second-difference penalty, relative to the mean diagonal of the data's normal
  // matrix (scale-free). Larger: smoother, straighter curves; smaller: follows noise.
  double smoothness = 1e-2;
  // Samples with a gray level >= this fraction of full scale in either frame are saturated.
  double saturation_fraction = 0.98;
  // Samples whose shorter-exposure gray level is less than this (fraction of full scale) above the
  // stack's background are near black (noise-dominated) and left out.
  double min_signal_fraction = 0.005;
  // Side of the square (px) around the blob's centroid whose pixels are sampled.
  int neighbourhood_px = 64;
  // The largest exposure ratio over all stacks must reach this (a ratio near 1 carries only the
  // slope of f, not its shape).
  double min_exposure_ratio = 1.5;
  // The sampled gray levels must span at least this fraction of full scale (max - min).
  double min_gray_span = 0.2;
  // At least this many sample equations.
  std::int64_t min_samples = 500;
  // Pixels per equation: the pixels of a pair of frames are sorted by an instrument that does not
  // depend on those two frames' noise (their rate in the stack's other frames) and summed in groups
  // of this many; per-pixel equations would be biased by the noise in their own gray levels.
  int group_size = 16;
  bool IsValid(std::string* why) const;
};

struct ResponseRecovery {
  InverseResponse curve;               // f on the knots, f(1) = 1, monotone
  double rms_relative_residual = -1.0; // rms of (f(M_a)/t_a - f(M_b)/t_b) / their mean
  std::int64_t samples = 0;            // sample equations used
  int stacks_used = 0;                 // stacks that gave samples
  int stacks_skipped = 0;              // stacks without a blob or without usable samples
  double gray_min = 0.0;               // lowest and highest gray level sampled (normalised)
  double gray_max = 0.0;
  double black_level = 0.0;            // M where f crosses 0 (the black level the data imply)
  double max_exposure_ratio = 0.0;     // largest t_b / t_a among the pairs used
  double condition_number = -1.0;      // of the stacked, weighted least-squares matrix
  // Linearity error over [gray_min, gray_max]: the largest deviation of f from the straight line
  // through its values at the two ends, % of f's rise over the range (EMVA 1288 style).
  double linearity_error_pct = 0.0;
  std::string BriefReport() const;
};

// Accumulates the sample equations of any number of stacks (one at a time, so a recording's frames
// need not stay in memory), then solves.
class ResponseRecoverer {
 public:
  // bit_depth: significant bits of the CV_16UC1 frames (8..16). Throws CheckError on invalid
  // options.
  ResponseRecoverer(int bit_depth, const ResponseOptions& options);

  // One static scene at `exposures_us` (one per frame, > 0; equal exposures are not paired). The
  // blob is located in the longest exposure (ComputeFeatures with `features`, identity response);
  // a stack without a blob is skipped. Returns the number of sample equations added.
  std::int64_t AddStack(const std::vector<cv::Mat>& frames, const std::vector<double>& exposures_us,
                        const FeatureOptions& features = FeatureOptions());

  // Solves. Throws ResponseError when the data do not determine f (see ResponseOptions).
  ResponseRecovery Solve() const;

  std::int64_t samples() const { return samples_; }

 private:
  struct Group {
    float t_a = 0.0f, t_b = 0.0f;  // exposures, ms
    std::vector<float> weights;    // summed interpolation weights: num_knots for a, then for b
  };
  // The neighbourhood around the blob of the longest exposure (nullopt: no blob); its background.
  std::optional<cv::Rect> BlobRegion(const std::vector<cv::Mat>& frames, const std::vector<double>& exposures_us,
                                     const FeatureOptions& features, double* background) const;
  // The grouped equations of exposure pair (a, b), t_a < t_b; returns the samples added.
  std::int64_t AddPair(const std::vector<cv::Mat>& frames, const std::vector<double>& exposures_us,
                       size_t a, size_t b, const cv::Rect& region, double background);
  // One weighted equation (interpolation weights `row`, exposures in ms, summed gray levels)
  // into the normal matrix and the statistics.
  void AddEquation(const std::vector<double>& row, double t_a, double t_b, double sum_a,
                   double sum_b);
  void KeepRow(const std::vector<double>& row, double t_a, double t_b);
  void CheckDetermined() const;  // throws ResponseError saying what the data lack
  int PinnedKnot() const;        // the knot held at f = 1 while solving
  double RmsRelativeResidual(const InverseResponse& curve) const;
  int bit_depth_;
  ResponseOptions options_;
  std::vector<double> normal_;  // num_knots^2 normal matrix of the weighted rows (column-major)
  std::vector<Group> rows_;     // a subsample (every stride_-th row) for the residual statistics
  std::int64_t groups_ = 0;
  std::int64_t stride_ = 1;
  std::int64_t samples_ = 0;
  std::int64_t pairs_seen_ = 0;
  std::int64_t excluded_saturated_ = 0;
  std::int64_t excluded_dark_ = 0;
  int stacks_used_ = 0;
  int stacks_skipped_ = 0;
  double gray_min_ = 1.0;
  double gray_max_ = 0.0;
  double max_ratio_ = 0.0;
};

// Convenience: every stack through one ResponseRecoverer.
struct ExposureStack {
  std::vector<cv::Mat> frames;       // CV_16UC1
  std::vector<double> exposures_us;  // one per frame
};
ResponseRecovery RecoverInverseResponse(const std::vector<ExposureStack>& stacks, int bit_depth,
                                        const ResponseOptions& options = ResponseOptions());

}  // namespace irdist
