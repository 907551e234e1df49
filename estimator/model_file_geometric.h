#pragma once
// model.yaml's `geometric:` terms beyond alpha and beta (fit.h GeometricModel): the blur's terms
// in u and the size's tilt term, read and written beside the model file's one parser
// (estimator/model_file.cc) that calls them. Estimator-internal: yaml-cpp shows here, so only .cc
// files include it.
//
//   geometric:
//     blur_u1_px2: 0.12              # format 4; both or neither (absent: a fixed blur)
//     blur_u2_px2: -0.03
//     blur_u3_px2: 0.004             # optional, only beside the two above
//     tilt_theta_deg: [0, 5, 10]     # optional: the tilt term's knots, increasing, in [0, 90)
//     tilt_var_px2: [0.003, 0, -0.01]  # its value at each knot, px^2

#include <yaml-cpp/yaml.h>

#include "estimator/fit.h"
#include "estimator/model_file_reader.h"

namespace irdist::model_file {

void EmitGeometricTerms(YAML::Emitter& out, const GeometricModel& g);
// Reads them from the `geometric:` map `g` of a file of `version`; throws ModelFileError.
void ReadGeometricTerms(const Reader& rd, const YAML::Node& g, int version, GeometricModel* geo);

}  // namespace irdist::model_file
