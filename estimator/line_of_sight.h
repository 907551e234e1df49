#pragma once
// The blob as the camera would see it turned about its centre to look straight at the IRED.
// The calibration holds the IRED on the optical axis; off the axis, at field angle
// alpha, a pinhole images the same small patch of directions stretched by 1/cos^2(alpha) along
// the radial and 1/cos(alpha) across it (image area per solid angle f^2 / cos^3(alpha)), and its
// aperture, seen obliquely, collects cos(alpha) of the flux (the image's irradiance falls as
// cos^4(alpha), the natural vignetting). Read as they are, an off-axis blob's size, shape and
// signal belong to no calibrated pose: at 50 mm off the axis at 1.5 m the size reads the distance
// 0.08% short, the signal 0.03% long, and a 15 deg tilt's axis ratio 0.1 deg off. The turned
// camera (same focal lengths, its axis along the blob's ray) sees the IRED on its axis, at its
// range r (camera centre to emitter) and at theta from its line of sight: the calibration's
// geometry. Its features come from the frame's by the local map of the turn at the blob (the blob
// is small against the field: the map's curvature across it is below 1e-6 of its size).

#include <functional>

#include <opencv2/core.hpp>

#include "estimator/features.h"

namespace irdist {

struct LineOfSight {
  double cos_field = 1.0;  // cosine of the angle between the optical axis and the blob's ray
  // d(turned camera's px) / d(frame px) at the blob: the identity on the axis.
  cv::Matx22d jacobian = cv::Matx22d::eye();
};

// The unit ray (camera frame: x along the rows, y down the columns, z along the optical axis) of
// a frame pixel position (the caller's undistortion: cv::undistortPoints with its intrinsics).
using RayOfPixel = std::function<cv::Vec3d(const cv::Point2d& frame_px)>;

// The turn at `blob_px`: the camera rotated about its centre by the smallest rotation that takes
// the blob's ray onto its axis, projecting with focal lengths (fx_px, fy_px) about its principal
// point; the Jacobian by central differences of +-0.5 px.
LineOfSight LineOfSightAt(const RayOfPixel& ray_of, const cv::Point2d& blob_px, double fx_px,
                          double fy_px);

// A frame's features as the turned camera sees them:
//  - the blob's second moments: the blur (in the sensor's pixels: optics, pixel, crosstalk; it
//    does not stretch with the field) taken out, the disc's matrix C mapped to J C J^T, the blur
//    put back; the moment ellipse's angle and axes follow (theta0 too where it came from them);
//  - the sums f00 and e_rel divided by cos(alpha) (the flux the turned camera's aperture takes);
//  - sigma from the signal's second moment, which scales as irradiance^2 x area = cos^5(alpha).
// The blur inside the moment variances: Features::size_blur_var_px2 where the blob fit set it,
// else the cumulants' measure blur_var_px2, else the pixel's 1/12. The centroid, background,
// peak and the measured blur stay the frame's (they are pixel quantities: position, saturation
// and health read them).
Features ToLineOfSight(const Features& frame, const LineOfSight& view);

}  // namespace irdist
