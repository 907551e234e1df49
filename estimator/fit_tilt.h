#pragma once
// The size law's tilt term (fit.h GeometricModel::tilt_var_px2): measured on the calibration's own
// poses, where d is known, as the blob fit's major-axis variance's departure from the law against
// the frame's own theta.

#include <string>
#include <vector>

#include "estimator/fit.h"

namespace irdist {

// A frame's own theta (deg) from its blob fit's disc axes (the variances less the blur the fit
// added); NaN without a blob fit (size_blur_var_px2 NaN) or a disc.
double FrameDiscThetaDeg(const Features& f);

// Knots need this many frames with a blob fit at their calibrated angle; a term needs 3 knots.
constexpr int kMinTiltKnotFrames = 8;
constexpr int kMinTiltKnots = 3;

// Fits *g's tilt term to the samples' major-axis variances less the law's (g's alpha and b(u) at
// the true d): least squares on the piecewise-linear basis in the frame's own theta, knots at the
// calibrated angles, each frame weighted by its variance's standard error (major_var_se_px2); each
// knot's value then shrunk by its noise (T (1 - se^2 / T^2)_+: a knot within its noise reads ~0).
// Leaves the term empty when the samples cannot give one or every knot shrinks to 0. Returns the
// fit's message ("" when none).
std::string FitTiltTerm(const std::vector<CalibrationSample>& samples, GeometricModel* g);

}  // namespace irdist
