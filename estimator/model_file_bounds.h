#pragma once
// The bounds of a model's numbers (base/bounds.h), one list shared by the model file's writer
// (SaveModel refuses a fit that lands outside, naming the parameter and why) and its reader
// (ModelFromYaml refuses the file at the key's line): a model irdist fit writes is a model every
// reader accepts.

#include <string>
#include <vector>

#include "estimator/fit.h"

namespace irdist {

// A number of a model outside its bound: the model file's key ("blur_calibration.
// fit_offset_u_px2", "provenance.t_meas_ms[1]") and what is wrong with it, range and physics.
struct ModelBoundFailure {
  std::string key;
  std::string message;
};

// Every bounded number of `model` and the cross-checks (the calibrated blur, with and without the
// blob fit's correction, a variance in (0, 16] px^2 over the calibrated distances; the window no
// larger than the ROI; the measurement exposures longer than the reference); empty when all hold.
std::vector<ModelBoundFailure> CheckModelBounds(const CalibrationModel& model);

}  // namespace irdist
