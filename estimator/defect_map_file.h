#pragma once
// model.yaml's features.defect_map (SceneOptions::defect_map, found by estimator/defect_map.h):
// its read and write, beside the model file's one parser (estimator/model_file.cc) that calls
// them. Estimator-internal: yaml-cpp shows here, so only .cc files include it.
//
//   defect_map:
//     roi_px: [x, y, width, height]   # the sensor region the map was found in (0 0 0 0: unknown)
//     pixels: [[x, y], ...]           # sensor coordinates
// Absent: no map (the file of a model without one is unchanged).

#include <yaml-cpp/yaml.h>

#include <string>

#include "estimator/model_file_reader.h"
#include "estimator/scene.h"

namespace irdist::model_file {

void EmitDefectMap(YAML::Emitter& out, const DefectMap& map);
// `parent`'s defect_map (parent_key for the errors' key path); throws ModelFileError.
DefectMap ReadDefectMap(const Reader& rd, const YAML::Node& parent, const std::string& parent_key);

}  // namespace irdist::model_file
