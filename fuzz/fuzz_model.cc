// libFuzzer target: model.yaml (estimator/model_file.h). A bad file must be a ModelFileError naming
// the file; a good one must lie inside the bounds table (estimator/model_file_bounds.h, the list
// the writer checks too) and survive a write and a read unchanged.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "estimator/model_file.h"
#include "estimator/model_file_bounds.h"

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
  if (!irdist::CheckModelBounds(model).empty()) __builtin_trap();  // accepted: inside the table
  const std::string again = irdist::ModelToYaml(model);
  if (irdist::ModelToYaml(irdist::ModelFromYaml(again, "again.yaml")) != again) __builtin_trap();
  return 0;
}
