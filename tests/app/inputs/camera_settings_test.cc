// The camera's settings from a rig file's camera: section: every key reaches the camera, the
// trigger source is the run's, the exposure check's spelling is its mode.
#include "app/inputs/camera_settings.h"

#include <gtest/gtest.h>

#include <utility>

namespace irdist {
namespace {

CameraConfig LabCamera() {
  CameraConfig c;
  c.pixel_format = "Mono12p";
  c.trigger_activation = "FallingEdge";
  c.black_level = 12;
  c.packet_size = 8192;
  c.roi_offset_x = 320;
  c.roi_offset_y = 256;
  c.roi_width = 256;
  c.roi_height = 192;
  c.trigger_in_readout = true;
  c.exposure_check = "readback";
  c.restore_after = false;
  return c;
}

TEST(CameraSettingsTest, EveryRigKeyReachesTheCamera) {
  const CameraSettings s = CameraSettingsOf(LabCamera(), "Line2");
  EXPECT_EQ(s.pixel_format, "Mono12p");
  EXPECT_EQ(s.trigger_source, "Line2");
  EXPECT_EQ(s.trigger_activation, "FallingEdge");
  EXPECT_EQ(s.black_level, 12.0);
  EXPECT_EQ(s.packet_size, 8192);
  EXPECT_EQ(s.offset_x, 320);
  EXPECT_EQ(s.offset_y, 256);
  EXPECT_EQ(s.width, 256);
  EXPECT_EQ(s.height, 192);
  EXPECT_TRUE(s.trigger_in_readout);
  EXPECT_EQ(s.exposure_check, ExposureCheck::kReadback);
  EXPECT_FALSE(s.restore_after);
}

// The run's trigger source wins over the rig's camera.trigger_source (a software trigger on the
// virtual rig, the station's line on a lab's).
TEST(CameraSettingsTest, TheTriggerSourceIsTheRunsOwn) {
  CameraConfig c = LabCamera();
  c.trigger_source = "Line1";
  EXPECT_EQ(CameraSettingsOf(c, "Software").trigger_source, "Software");
}

TEST(CameraSettingsTest, TheExposureCheckSpellingsAreItsModes) {
  CameraConfig c;
  const std::pair<const char*, ExposureCheck> modes[] = {{"auto", ExposureCheck::kAuto},
                                                         {"chunk", ExposureCheck::kChunk},
                                                         {"readback", ExposureCheck::kReadback},
                                                         {"none", ExposureCheck::kNone}};
  for (const auto& [name, mode] : modes) {
    c.exposure_check = name;
    EXPECT_EQ(CameraSettingsOf(c, "Line1").exposure_check, mode) << name;
  }
  EXPECT_TRUE(CameraSettingsOf(c, "Line1").width == 0);  // the full sensor by default
}

}  // namespace
}  // namespace irdist
