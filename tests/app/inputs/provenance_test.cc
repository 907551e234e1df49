// Model provenance: the check validate, playback and measure make, and what a rig says.
#include "app/inputs/provenance.h"

#include <gtest/gtest.h>

namespace irdist {
namespace {

ModelProvenance Calibrated() {
  ModelProvenance p;
  p.known = true;
  p.rig_name = "virtual";
  p.camera_serial = "IRDV0001";
  p.pixel_format = "Mono12";
  p.roi_offset_x = 512;
  p.roi_offset_y = 384;
  p.roi_width = 256;
  p.roi_height = 256;
  return p;
}

std::string MismatchMessage(const ModelProvenance& actual) {
  try {
    CheckModelProvenance(Calibrated(), "cal/model.yaml", actual, "rig other", false);
  } catch (const ModelMismatchError& e) {
    return e.what();
  }
  return "";
}

TEST(CheckModelProvenance, SameSetupPasses) {
  EXPECT_NO_THROW(CheckModelProvenance(Calibrated(), "m", Calibrated(), "rig", false));
}

TEST(CheckModelProvenance, OtherSerialIsRefusedNamingBoth) {
  ModelProvenance other = Calibrated();
  other.camera_serial = "IRDV0002";
  const std::string message = MismatchMessage(other);
  EXPECT_NE(message.find("IRDV0001"), std::string::npos) << message;
  EXPECT_NE(message.find("IRDV0002"), std::string::npos) << message;
  EXPECT_NE(message.find("cal/model.yaml"), std::string::npos) << message;
  EXPECT_NE(message.find("--allow-model-mismatch"), std::string::npos) << message;
}

TEST(CheckModelProvenance, OtherRoiAndPixelFormatAreRefused) {
  ModelProvenance other = Calibrated();
  other.roi_offset_x = 500;
  EXPECT_NE(MismatchMessage(other).find("[500, 384, 256, 256]"), std::string::npos);
  other = Calibrated();
  other.pixel_format = "Mono8";
  EXPECT_NE(MismatchMessage(other).find("Mono12 vs Mono8"), std::string::npos);
  other = Calibrated();
  other.roi_width = 0;
  EXPECT_NE(MismatchMessage(other).find("full sensor"), std::string::npos);
}

TEST(CheckModelProvenance, OverrideWarnsInstead) {
  ModelProvenance other = Calibrated();
  other.camera_serial = "IRDV0002";
  std::string warning;
  EXPECT_NO_THROW(CheckModelProvenance(Calibrated(), "m", other, "rig", true, &warning));
  EXPECT_NE(warning.find("IRDV0002"), std::string::npos);
}

// Regression: a model from another rig name passed silently. The same camera setup under
// another rig name (virtual-offset shares virtual's camera) is used, with a warning naming both.
TEST(CheckModelProvenance, AnotherRigNameWarns) {
  ModelProvenance other = Calibrated();
  other.rig_name = "virtual-offset";
  std::string warning;
  EXPECT_NO_THROW(CheckModelProvenance(Calibrated(), "m.yaml", other, "rig virtual-offset", false,
                                       &warning));
  EXPECT_NE(warning.find("calibrated on rig virtual,"), std::string::npos) << warning;
  EXPECT_NE(warning.find("(rig virtual-offset)"), std::string::npos) << warning;
  warning.clear();
  CheckModelProvenance(Calibrated(), "m.yaml", Calibrated(), "rig virtual", false, &warning);
  EXPECT_EQ(warning, "");
}

TEST(CheckModelProvenance, UnknownSideIsNotCompared) {
  ModelProvenance old;  // a model file written before provenance
  ModelProvenance other = Calibrated();
  other.camera_serial = "X";
  EXPECT_NO_THROW(CheckModelProvenance(old, "m", other, "rig", false));
  other = Calibrated();
  other.camera_serial = "";  // a hardware camera not opened yet
  EXPECT_NO_THROW(CheckModelProvenance(Calibrated(), "m", other, "rig", false));
}

TEST(ProvenanceOfRig, TakesTheCameraSection) {
  Rig rig;
  rig.name = "lab";
  rig.camera.pixel_format = "Mono8";
  rig.camera.roi_offset_x = 10;
  rig.camera.roi_width = 128;
  const ModelProvenance p = ProvenanceOfRig(rig, "S1");
  EXPECT_TRUE(p.known);
  EXPECT_EQ(p.rig_name, "lab");
  EXPECT_EQ(p.camera_serial, "S1");
  EXPECT_EQ(p.pixel_format, "Mono8");
  EXPECT_EQ(p.roi_offset_x, 10);
  EXPECT_EQ(p.roi_width, 128);
}

}  // namespace
}  // namespace irdist
