#pragma once
// Single exposures of the rig's camera, for snap and view (without a model, or on the whole
// sensor): the camera opened for them, one frame after another, and the signal line both print.

#include <iosfwd>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "acquisition/bracket.h"
#include "app/live/live_camera.h"
#include "estimator/features.h"

namespace irdist {

// The rig's camera opened for single exposures of `exposure_ms` (snap, view without a model);
// `at` and `time_scale` as LiveCameraOptions' (the IRED's pose on a virtual rig, its clock).
std::unique_ptr<LiveCamera> OpenForSingleExposures(const std::string& rig,
                                                   const std::vector<double>& at,
                                                   double exposure_ms, double time_scale,
                                                   std::ostream& err);

// One exposure after another on a live camera (snap, view without a model, view's whole sensor).
class SingleExposure {
 public:
  SingleExposure(LiveCamera& live, double exposure_ms, std::ostream& notices);
  // The next frame; throws CameraError when two captures in a row bring none.
  cv::Mat Next();

 private:
  LiveCamera& live_;
  std::unique_ptr<BracketCapture> capture_;
};

// The signal line: peak and background as fractions of full scale, saturated pixels.
std::string LevelLine(const Features& f);

}  // namespace irdist
