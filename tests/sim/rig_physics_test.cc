#include "sim/rig_physics.h"

#include <fstream>
#include <string>

#include <gtest/gtest.h>

namespace irdist::sim {
namespace {

std::string WriteRig(const std::string& name, const std::string& text) {
  const std::string path = std::string(IRDIST_BINARY_DIR) + "/sim_rig_physics_" + name + ".yaml";
  std::ofstream(path) << text;
  return path;
}

TEST(RigPhysics, DefaultsAreValid) {
  std::string why;
  EXPECT_TRUE(RigPhysics{}.IsValid(&why)) << why;
  EXPECT_TRUE(EmitterOptions{}.IsValid(&why)) << why;
  EXPECT_TRUE(OpticsOptions{}.IsValid(&why)) << why;
  EXPECT_TRUE(SensorOptions{}.IsValid(&why)) << why;
  EXPECT_TRUE(CameraOptions{}.IsValid(&why)) << why;
}

TEST(RigPhysics, InvalidValuesAreRejectedWithAReason) {
  RigPhysics p;
  p.sensor.quantum_efficiency = 1.5;
  std::string why;
  EXPECT_FALSE(p.IsValid(&why));
  EXPECT_NE(why.find("quantum_efficiency"), std::string::npos);
  p = RigPhysics{};
  p.camera.serial = "a-serial-far-too-long";
  EXPECT_FALSE(p.IsValid(&why));
  p = RigPhysics{};
  p.time_scale = 0.0;
  EXPECT_FALSE(p.IsValid(&why));
  p = RigPhysics{};
  p.camera.exposure_write_delay_ms = -1.0;
  EXPECT_FALSE(p.IsValid(&why));
  EXPECT_NE(why.find("exposure_write_delay_ms"), std::string::npos);
}

TEST(RigPhysics, ShippedVirtualRigLoadsAndMatchesTheDefaults) {
  const RigPhysics p = LoadRigPhysics(std::string(IRDIST_SOURCE_DIR) + "/recipes/rigs/virtual.yaml");
  const RigPhysics d;
  EXPECT_EQ(p.time_scale, d.time_scale);
  EXPECT_EQ(p.emitter.diameter_mm, d.emitter.diameter_mm);
  EXPECT_EQ(p.optics.filter_transmission, d.optics.filter_transmission);
  EXPECT_EQ(p.sensor.system_gain_dn_per_e, d.sensor.system_gain_dn_per_e);
  EXPECT_EQ(p.sensor.width_px, 1280);
  EXPECT_EQ(p.camera.serial, d.camera.serial);
}

TEST(RigPhysics, ReadsValuesAndLeavesOthersAtDefaults) {
  const std::string path = WriteRig("values",
                                    "name: t\n"
                                    "virtual:\n"
                                    "  time_scale: 20\n"
                                    "  seed: 99\n"
                                    "  serial: ABC123\n"
                                    "  emitter:\n"
                                    "    pattern: cos_power\n"
                                    "    pattern_cos_power: 2.5\n"
                                    "  sensor:\n"
                                    "    adc_bits: 10\n"
                                    "    black_level_dn: 4\n"
                                    "  camera:\n"
                                    "    lost_packet_ratio: 0.05\n"
                                    "    exposure_write_delay_ms: 20\n"
                                    "  station:\n"
                                    "    anything: goes here\n");
  const RigPhysics p = LoadRigPhysics(path);
  EXPECT_EQ(p.time_scale, 20.0);
  EXPECT_EQ(p.sensor.seed, 99u);
  EXPECT_EQ(p.camera.serial, "ABC123");
  EXPECT_EQ(p.emitter.pattern, EmissionPattern::kCosPower);
  EXPECT_EQ(p.emitter.pattern_cos_power, 2.5);
  EXPECT_EQ(p.sensor.adc_bits, 10);
  EXPECT_EQ(p.camera.lost_packet_ratio, 0.05);
  EXPECT_EQ(p.camera.exposure_write_delay_ms, 20.0);
  EXPECT_EQ(p.optics.focal_length_mm, OpticsOptions{}.focal_length_mm);
}

TEST(RigPhysics, NoVirtualSectionGivesDefaults) {
  const RigPhysics p = LoadRigPhysics(WriteRig("none", "name: hw\ncamera:\n  id: x\n"));
  EXPECT_EQ(p.sensor.full_well_e, SensorOptions{}.full_well_e);
}

void ExpectError(const std::string& text, const std::string& name, const std::string& where,
                 const std::string& what) {
  const std::string path = WriteRig(name, text);
  try {
    LoadRigPhysics(path);
    ADD_FAILURE() << "no error for " << text;
  } catch (const RigFileError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(path + ":" + where), std::string::npos) << message;
    EXPECT_NE(message.find(what), std::string::npos) << message;
  }
}

TEST(RigPhysics, UnknownKeyNamesFileAndLine) {
  ExpectError("virtual:\n  optics:\n    focal_lenght_mm: 16\n", "unknown", "3",
              "unknown key 'focal_lenght_mm'");
  ExpectError("virtual:\n  colour: red\n", "unknown_top", "2", "unknown key 'colour'");
}

TEST(RigPhysics, BadValueNamesFileAndLine) {
  ExpectError("virtual:\n  sensor:\n    full_well_e: lots\n", "badvalue", "3", "full_well_e");
  ExpectError("virtual:\n  emitter:\n    pattern: square\n", "badpattern", "3", "pattern");
  ExpectError("virtual:\n  sensor:\n    quantum_efficiency: 2\n", "range", "", "quantum_efficiency");
}

// The sensor's fixed-pattern noise: off by default, on in virtual-fpn.yaml, range-checked.
TEST(RigPhysics, FixedPatternNoiseKeys) {
  EXPECT_EQ(RigPhysics{}.sensor.prnu_percent, 0.0);
  EXPECT_EQ(RigPhysics{}.sensor.dsnu_e, 0.0);
  const RigPhysics p =
      LoadRigPhysics(std::string(IRDIST_SOURCE_DIR) + "/recipes/rigs/virtual-fpn.yaml");
  EXPECT_EQ(p.sensor.prnu_percent, 1.0);
  EXPECT_EQ(p.sensor.dsnu_e, 3.0);
  ExpectError("virtual:\n  sensor:\n    dsnu_e: -1\n", "dsnu", "", "dsnu_e");
  ExpectError("virtual:\n  sensor:\n    prnu_percent: 50\n", "prnu", "", "prnu_percent");
}

TEST(RigPhysics, OwnersSubsectionsAreLeftToTheirOwners) {
  // virtual.devices and virtual.station are read strictly by the emulators, not here.
  const RigPhysics p = LoadRigPhysics(WriteRig(
      "owners", "virtual:\n  devices:\n    anything: 1\n  station:\n    whatever: 2\n"
                "  sensor:\n    adc_bits: 10\n"));
  EXPECT_EQ(p.sensor.adc_bits, 10);
}

TEST(RigPhysics, ErrorsAreInputErrorsWithTheLine) {
  const std::string path =
      WriteRig("input_error", "virtual:\n  camera:\n    readout_ms: 3\n    readout_ms: 4\n");
  try {
    LoadRigPhysics(path);
    ADD_FAILURE() << "a duplicate key was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.File(), path);
    EXPECT_EQ(e.Line(), 4);
    EXPECT_NE(e.Message().find("readout_ms"), std::string::npos) << e.what();
  }
  ExpectError("virtual:\n  sensor:\n    adc_bits: 10.5\n", "integer", "3", "adc_bits");
  ExpectError("virtual:\n  seed: -3\n", "seed", "2", "seed");
}

TEST(RigPhysics, MissingFileIsATypedError) {
  EXPECT_THROW(LoadRigPhysics("/nonexistent/rig.yaml"), RigFileError);
}

}  // namespace
}  // namespace irdist::sim
