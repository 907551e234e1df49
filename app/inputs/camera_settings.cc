#include "app/inputs/camera_settings.h"

namespace irdist {

CameraSettings CameraSettingsOf(const CameraConfig& c, const std::string& trigger_source) {
  CameraSettings s;
  s.pixel_format = c.pixel_format;
  s.trigger_source = trigger_source;
  s.trigger_activation = c.trigger_activation;
  s.black_level = c.black_level;
  s.packet_size = c.packet_size;
  s.offset_x = c.roi_offset_x;
  s.offset_y = c.roi_offset_y;
  s.width = c.roi_width;
  s.height = c.roi_height;
  s.trigger_in_readout = c.trigger_in_readout;
  // rig.cc refused any other spelling at its line.
  s.exposure_check = ParseExposureCheck(c.exposure_check).value_or(ExposureCheck::kAuto);
  s.restore_after = c.restore_after;
  return s;
}

}  // namespace irdist
