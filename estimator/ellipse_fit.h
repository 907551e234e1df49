#pragma once
// An ellipse fitted to a blob (Features' moment, contour and model-fit ellipses), in its own
// header so the kModelFit fit (disc_fit.h) and the features (features.h) share it without
// including each other.

#include <opencv2/core.hpp>

namespace irdist {

struct EllipseFit {
  bool valid = false;
  cv::Point2d center_px;
  double major_px = 0.0;  // full axis lengths
  double minor_px = 0.0;
  double angle_deg = 0.0;   // direction of the major axis in the image, degrees from +x
  double theta0_deg = 0.0;  // acos(minor / major)
};

}  // namespace irdist
