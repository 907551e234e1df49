#pragma once
// What the measure integration tests share: the small calibration they make their model with, and
// the JSON lines of `irdist measure --json`.

#include <yaml-cpp/yaml.h>

#include <sstream>
#include <string>
#include <vector>

namespace irdist::testing {

// A 3-distance x 4-angle x 2-current calibration on the virtual rig, fitted after recording
// (the measure tests and integration/calibrate_validate); `slides_mm` another list of distances.
inline std::string SmallCalibrationRecipe(const std::string& name,
                                          const std::string& slides_mm = "[1500, 2000, 2500]") {
  return "name: " + name + R"(
rig: virtual
after: fit
axes:
  slide_mm: )" + slides_mm + R"(
  theta_deg: [0, 10, 20, 30]
  bias_ma: [475, 500]
bracket:
  t_ref_ms: 8
  t_meas_ms: [30, 33, 36]
settle:
  after_move_ms: 200
  after_current_ms: 500
)";
}

// The JSON objects of an output (lines starting with '{'), parsed.
inline std::vector<YAML::Node> JsonLines(const std::string& output) {
  std::vector<YAML::Node> objects;
  std::istringstream in(output);
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty() && line[0] == '{') objects.push_back(YAML::Load(line));
  }
  return objects;
}

}  // namespace irdist::testing
