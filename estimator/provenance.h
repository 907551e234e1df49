#pragma once
// Where a calibration comes from: the rig, the camera (vendor, model, serial), how its frames were
// taken (pixel format, bit depth, region of interest), the recipe, the date, and the bracket the
// model was calibrated with (t_r and the t_n), which `irdist measure` takes by default. Stored
// as the `provenance:` block of model.yaml (docs/estimator.md); absent in older files.

#include <string>
#include <vector>

namespace irdist {

struct ModelProvenance {
  bool known = false;  // false: a model file without the block (written before it existed)
  std::string rig_name;
  std::string rig_path;
  std::string camera_vendor;
  std::string camera_model;
  std::string camera_serial;
  std::string pixel_format;  // GenICam PixelFormat, "Mono12"
  int bit_depth = 0;
  // Region of interest [offset_x, offset_y, width, height] in sensor pixels; width 0 = full sensor.
  int roi_offset_x = 0, roi_offset_y = 0, roi_width = 0, roi_height = 0;
  std::string recipe_path;
  std::string calibration_date;  // ISO 8601 UTC start of the calibration's recording
  // The calibration's bracket: reference exposure and measurement exposures, trigger order.
  double t_ref_ms = 0.0;
  std::vector<double> t_meas_ms;
  bool retake_reference = false;
};

}  // namespace irdist
