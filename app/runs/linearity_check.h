#pragma once
// A calibration's first pose: before its first bracket, the camera's linearity is measured on the
// lit IRED (acquisition/linearity.h, EMVA 1288's linearity error, docs/devices/README.md), kept in
// the recording (linearity.yaml) and printed. Above the limit the calibration stops, naming the
// probable causes, unless told to go on (--allow-nonlinear): a LUT, a gamma curve or a contrast
// feature irdist does not know would bend every gray level the model is fitted to.

#include <functional>
#include <ostream>
#include <string>

#include "acquisition/linearity.h"

namespace irdist {

class AravisCamera;

struct FirstPoseLinearityOptions {
  std::string recording_dir;     // linearity.yaml is written here
  bool allow_nonlinear = false;  // --allow-nonlinear: report, then go on
  double probe_exposure_us = 0;  // the series' first probe (the bracket's reference exposure)
  int bit_depth = 12;            // the pixel format's
  // The first problem, naming the field, in *why (empty when valid).
  bool IsValid(std::string* why) const;
};

// Whether a calibration's recording still needs the series: a new one does; a resumed one does
// unless its linearity.yaml says the series passed (a run refused, then resumed, measures again).
bool NeedsFirstPoseLinearity(const std::string& recording_dir, bool resume);

// The file's text: every figure of the series and each point.
std::string LinearityYaml(const LinearityResult& result);

// Runs the series on `camera`, each frame fired by `fire` (the rig's trigger), writes
// RECORDING/linearity.yaml and one line on `out`. Throws CameraError when the linearity error is
// above the limit and the options do not allow it; a scene with no light is reported, not refused.
LinearityResult CheckFirstPoseLinearity(AravisCamera& camera, const std::function<void()>& fire,
                                        const FirstPoseLinearityOptions& options,
                                        std::ostream& out);

}  // namespace irdist
