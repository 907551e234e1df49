// libFuzzer target: model.yaml (estimator/model_file.h). A bad file must be a ModelFileError naming
// the file; a good one must survive a write and a read unchanged.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "estimator/model_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  irdist::CalibrationModel model;
  try {
    model = irdist::ModelFromYaml(text, "fuzz/model.yaml");
  } catch (const irdist::ModelFileError& error) {
    if (error.path() != "fuzz/model.yaml") __builtin_trap();
    return 0;
  }
  for (const auto& m : model.models) {
    for (double c : m.coefficients) {
      if (!std::isfinite(c)) __builtin_trap();  // the load lets no NaN or inf through
    }
  }
  const std::string again = irdist::ModelToYaml(model);
  if (irdist::ModelToYaml(irdist::ModelFromYaml(again, "again.yaml")) != again) __builtin_trap();
  return 0;
}
