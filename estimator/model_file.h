#pragma once
// model.yaml: the calibration (every coefficient, sigma, the scalings, the ROI policy and its
// parameters, the calibrated ranges, fit statistics), written with max_digits10 so that reading it
// back gives the same doubles bit for bit. Layout in docs/estimator.md.

#include <string>

#include "estimator/fit.h"
#include "estimator/model_file_error.h"

namespace irdist {

// 2 adds features.moment_method, features.aperture_margin_px and theta_correction. Version 1 files
// still load: those keys take their defaults and the model has no theta correction.
// 3 adds features.response_scope (e_rel_only | all_pixels); version 1 and 2 files load as
// e_rel_only (the inverse response entered E_rel only).
constexpr int kModelFormatVersion = 4;  // 4: geometric blur varying with distance, health
constexpr int kOldestModelFormatVersion = 1;

// The YAML text of a model (what SaveModel writes).
std::string ModelToYaml(const CalibrationModel& model);
// Parses YAML text; `path` only names the source in errors.
CalibrationModel ModelFromYaml(const std::string& text, const std::string& path);

void SaveModel(const CalibrationModel& model, const std::string& path);  // throws ModelFileError
CalibrationModel LoadModel(const std::string& path);                     // throws ModelFileError

}  // namespace irdist
