#pragma once
// The camera's settings (acquisition/camera.h) from a rig file's `camera:` section: the one
// mapping every live command uses (calibrate and validate's recorder, measure and view's live
// camera). Apart from rig.h, which the rig and recipe fuzz targets compile without OpenCV.

#include <string>

#include "acquisition/camera.h"
#include "app/inputs/rig.h"

namespace irdist {

// Format, trigger activation and overlap, black level, packet size and region from `camera`,
// with the FrameStart source the run fires (devices/station_setup.h RigTriggerSource); exposure
// and buffers stay CameraSettings' defaults for the caller.
CameraSettings CameraSettingsOf(const CameraConfig& camera, const std::string& trigger_source);

}  // namespace irdist
