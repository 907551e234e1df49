#pragma once
// The kModelFit ellipse (estimator-internal, EllipseMethod::kModelFit in features.h): a uniformly
// bright elliptical disc blurred by a Gaussian and integrated over each pixel, fitted by
// Levenberg-Marquardt to the blob's pixels, started from the moment ellipse.

#include <opencv2/core.hpp>

#include "estimator/ellipse_fit.h"

namespace irdist {

// The blob's background-subtracted centroid and second moments (px, px^2) the fit starts from.
struct DiscMoments {
  double cx = 0.0, cy = 0.0, sxx = 0.0, syy = 0.0, sxy = 0.0;
};

// theta0 of an ellipse: acos(minor / major) in degrees (0 for a degenerate one).
double Theta0FromAxes(double minor, double major);

// theta0 (deg) of a disc from its variances along its axes (px^2, the blur removed): acos of the
// axes' ratio, a negative minor variance read as 0; NaN unless the major variance is > 0.
double Theta0FromVariances(double minor_var_px2, double major_var_px2);

// Fits the disc model to the pixels of `rect` (normalised gray levels); start from the moment
// ellipse (centre, covariance) or the half-maximum contour, with blur s0. Sets the fitted
// ellipse, its blur sigma (px) and the rms residual; returns false when the fit fails.
bool FitDisc(const cv::Mat& image, const cv::Rect& rect, double max_gray, const DiscMoments& m,
             const EllipseFit& contour, double background, double peak, double s0,
             EllipseFit* fit, double* blur_px, double* rms);

}  // namespace irdist
