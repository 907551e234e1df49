#pragma once
// model.yaml's optional `fitness:` block (CalibrationFitness, estimator/fitness_figure.h): its read and
// write, beside the model file's one parser (estimator/model_file.cc) that calls them.
// Estimator-internal: yaml-cpp shows here, so only .cc files include it.
//
//   fitness:
//     passed: true
//     reduced_chi2: 0.93          # chi-square / dof of the model on its own calibration poses
//     dof: 180
//     limit: 1.27                 # the chi-square quantile / dof at tail_probability
//     pose_limit: 22.5            # one pose's chi-square limit (tail_probability / poses)
//     tail_probability: 0.001
//     size_floor: 0.004           # model-error floors, relative
//     difference_floor: 0.004
//     poses: 64
//     poses_over: 0
//     cause: ""                   # the probable cause when it did not pass
//     worst_poses:
//       - {slide_mm: 3000, pan_deg: 35, tilt_deg: 0, bias_ma: 475, chi2: 9.1, channels: 4,
//          scatter_ratio: 1.3, channel: minor, residual_percent: 0.41}
// Absent (models before it, or not assessed): CalibrationFitness::assessed is false.

#include <yaml-cpp/yaml.h>

#include "estimator/fitness_figure.h"
#include "estimator/model_file_reader.h"

namespace irdist::model_file {

void EmitFitness(YAML::Emitter& out, const CalibrationFitness& fitness);  // nothing unassessed
// The root's `fitness:` (not assessed when absent); throws ModelFileError.
CalibrationFitness ReadFitness(const Reader& rd, const YAML::Node& root);

}  // namespace irdist::model_file
