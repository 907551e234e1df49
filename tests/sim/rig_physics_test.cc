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
  // The Airy key: read, refused out of its range and beside the defocus disc, at its line.
  const RigPhysics airy = LoadRigPhysics(WriteRig(
      "airy", "virtual:\n  optics:\n    psf_sigma_px: 0.5\n    airy_first_zero_px: 1.2\n"));
  EXPECT_EQ(airy.optics.airy_first_zero_px, 1.2);
  ExpectError("virtual:\n  optics:\n    airy_first_zero_px: 7\n", "airy_range", "3",
              "airy_first_zero_px must be 0 (no Airy pattern) or lie in [0.3, 3]");
  ExpectError("virtual:\n  optics:\n    defocus_disc: true\n    airy_first_zero_px: 1\n",
              "airy_disc", "4", "needs psf_sigma_px >= 0.3 and no defocus_disc");
}

// The camera's pixel-shaping faults (a LUT left on, a gamma it cannot switch off): off by
// default, read, range-checked at their line.
TEST(RigPhysics, CameraCurveFaultKeys) {
  EXPECT_FALSE(CameraOptions{}.lut_enable);
  EXPECT_EQ(CameraOptions{}.fixed_gamma, 1.0);
  const RigPhysics p = LoadRigPhysics(WriteRig(
      "curves", "virtual:\n  camera:\n    lut_enable: true\n    lut_gamma: 0.5\n"
                "    fixed_gamma: 0.8\n"));
  EXPECT_TRUE(p.camera.lut_enable);
  EXPECT_EQ(p.camera.lut_gamma, 0.5);
  EXPECT_EQ(p.camera.fixed_gamma, 0.8);
  ExpectError("virtual:\n  camera:\n    fixed_gamma: 0\n", "badgamma", "3", "fixed_gamma");
  ExpectError("virtual:\n  camera:\n    lut_enable: maybe\n", "badlut", "3", "lut_enable");
}

// The camera's transport faults: exposure chunks dropped from a frame on, packet resend off; both
// off by default, read, checked at their line.
TEST(RigPhysics, CameraChunkAndResendFaultKeys) {
  EXPECT_EQ(CameraOptions{}.drop_exposure_chunks_from_frame, 0);
  EXPECT_TRUE(CameraOptions{}.packet_resend);
  const RigPhysics p = LoadRigPhysics(WriteRig(
      "chunks", "virtual:\n  camera:\n    drop_exposure_chunks_from_frame: 7\n"
                "    packet_resend: false\n"));
  EXPECT_EQ(p.camera.drop_exposure_chunks_from_frame, 7);
  EXPECT_FALSE(p.camera.packet_resend);
  ExpectError("virtual:\n  camera:\n    drop_exposure_chunks_from_frame: -1\n", "baddrop", "3",
              "drop_exposure_chunks_from_frame");
  ExpectError("virtual:\n  camera:\n    packet_resend: sometimes\n", "badresend", "3",
              "packet_resend");
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

// The pixel's sensitive square (a fill factor): the whole pixel by default, read, range-checked.
TEST(RigPhysics, PixelApertureKey) {
  EXPECT_EQ(RigPhysics{}.sensor.pixel_aperture, 1.0);
  const RigPhysics p = LoadRigPhysics(
      WriteRig("aperture", "name: t\nvirtual:\n  sensor:\n    pixel_aperture: 0.7\n"));
  EXPECT_EQ(p.sensor.pixel_aperture, 0.7);
  ExpectError("virtual:\n  sensor:\n    pixel_aperture: 0.2\n", "aperture_low", "",
              "pixel_aperture");
  ExpectError("virtual:\n  sensor:\n    pixel_aperture: 1.5\n", "aperture_high", "",
              "pixel_aperture");
}

// The crosstalk's kernel shape: the lattice walk by default, the sampled Gaussian by name, and
// any other name refused at its line with the two it may be.
TEST(RigPhysics, CrosstalkShapeKey) {
  EXPECT_EQ(RigPhysics{}.sensor.crosstalk_shape, CrosstalkShape::kLatticeWalk);
  const RigPhysics p = LoadRigPhysics(WriteRig(
      "shape", "name: t\nvirtual:\n  sensor:\n    crosstalk_sigma_px: 1.0\n"
               "    crosstalk_shape: sampled_gaussian\n"));
  EXPECT_EQ(p.sensor.crosstalk_shape, CrosstalkShape::kSampledGaussian);
  ExpectError("virtual:\n  sensor:\n    crosstalk_shape: gaussian\n", "badshape", "3",
              "sampled_gaussian");
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

// The lab's scene (docs/virtual-rig.md "A lab's scene"): off by default, every key read.
TEST(RigPhysics, LabSceneKeysAreOffByDefaultAndRead) {
  std::string why;
  EXPECT_TRUE(LabSceneOptions{}.IsValid(&why)) << why;
  EXPECT_TRUE(DefectPixelOptions{}.IsValid(4095, &why)) << why;
  const RigPhysics d;
  EXPECT_EQ(d.sensor.defects.Count(), 0);
  EXPECT_FALSE(d.scene.ambient.On());
  EXPECT_FALSE(d.scene.reflection.On());
  EXPECT_FALSE(d.scene.second_source.On());
  EXPECT_FALSE(d.scene.occluder.On());
  const RigPhysics p = LoadRigPhysics(WriteRig(
      "lab", "virtual:\n"
             "  sensor:\n"
             "    hot_pixels: 20\n"
             "    hot_rate_e_per_s: [180000, 300000]\n"
             "    stuck_pixels: 10\n"
             "    stuck_level_dn: [1000, 4095]\n"
             "    defect_seed: 7\n"
             "    defects_near_blob: 3\n"
             "    near_blob_radius_px: 12\n"
             "  scene:\n"
             "    ambient: {center_e_per_s: 6000, gradient_x_percent: 66, gradient_y_percent: -10}\n"
             "    reflection: {plane_below_mm: 8.3, reflectance: 0.2}\n"
             "    second_source: {position_mm: [40, 0, 2000], diameter_mm: 5, "
             "intensity_mw_sr: 14}\n"
             "    occluder: {covered_fraction: 0.15, edge_angle_deg: 270}\n"));
  EXPECT_EQ(p.sensor.defects.hot_pixels, 20);
  EXPECT_EQ(p.sensor.defects.hot_rate_e_per_s[1], 300000.0);
  EXPECT_EQ(p.sensor.defects.stuck_pixels, 10);
  EXPECT_EQ(p.sensor.defects.stuck_level_dn[0], 1000.0);
  EXPECT_EQ(p.sensor.defects.defect_seed, 7u);
  EXPECT_EQ(p.sensor.defects.defects_near_blob, 3);
  EXPECT_EQ(p.sensor.defects.near_blob_radius_px, 12.0);
  EXPECT_EQ(p.scene.ambient.center_e_per_s, 6000.0);
  EXPECT_EQ(p.scene.ambient.gradient_x_percent, 66.0);
  EXPECT_EQ(p.scene.ambient.gradient_y_percent, -10.0);
  EXPECT_EQ(p.scene.reflection.plane_below_mm, 8.3);
  EXPECT_EQ(p.scene.reflection.reflectance, 0.2);
  EXPECT_EQ(p.scene.second_source.position_mm[0], 40.0);
  EXPECT_EQ(p.scene.second_source.position_mm[2], 2000.0);
  EXPECT_EQ(p.scene.second_source.diameter_mm, 5.0);
  EXPECT_EQ(p.scene.second_source.intensity_mw_sr, 14.0);
  EXPECT_EQ(p.scene.occluder.covered_fraction, 0.15);
  EXPECT_EQ(p.scene.occluder.edge_angle_deg, 270.0);
}

// Every bad lab key is refused at its own line (or its subsection's first key's, for a
// combination of keys).
TEST(RigPhysics, BadLabSceneKeysNameFileAndLine) {
  ExpectError("virtual:\n  scene:\n    reflection:\n      reflectance: 1.5\n", "lab1", "4",
              "virtual.scene.reflection.reflectance must lie in [0, 1]");
  ExpectError("virtual:\n  scene:\n    reflection:\n      plane_below_mm: .nan\n", "lab2", "4",
              "plane_below_mm");
  ExpectError("virtual:\n  scene:\n    occluder:\n      covered_fraction: 0.99\n", "lab3", "4",
              "covered_fraction must lie in [0, 0.95]");
  ExpectError("virtual:\n  scene:\n    ambient:\n      center_e_per_s: -5\n", "lab4", "4",
              "center_e_per_s");
  ExpectError("virtual:\n  scene:\n    ambient:\n      gradient_x_percent: 150\n"
              "      gradient_y_percent: 150\n", "lab5", "4", "|gx| + |gy| <= 200");
  ExpectError("virtual:\n  scene:\n    second_source:\n      position_mm: [1, 2]\n", "lab6",
              "4", "position_mm must be a list of 3 numbers");
  ExpectError("virtual:\n  scene:\n    second_source:\n      position_mm: [1, 2, -50]\n",
              "lab7", "4", "in front of the camera");
  ExpectError("virtual:\n  scene:\n    second_source:\n      position_mm: [0, 0, 1000]\n"
              "      diameter_mm: 60\n", "lab16", "5", "diameter_mm must lie in [0.001, 0.05 z]");
  ExpectError("virtual:\n  scene:\n    second_source:\n      intensity_mw_sr: inf\n", "lab8",
              "4", "intensity_mw_sr");
  ExpectError("virtual:\n  scene:\n    mirror: {}\n", "lab9", "3", "unknown key 'mirror'");
  ExpectError("virtual:\n  sensor:\n    hot_pixels: -1\n", "lab10", "3", "hot_pixels must be");
  ExpectError("virtual:\n  sensor:\n    hot_rate_e_per_s: [3, 2]\n", "lab11", "3",
              "hot_rate_e_per_s must be [lo, hi]");
  ExpectError("virtual:\n  sensor:\n    stuck_pixels: 2\n    stuck_level_dn: [0, 5000]\n",
              "lab12", "4", "stuck_level_dn");
  ExpectError("virtual:\n  sensor:\n    hot_pixels: 2\n    defects_near_blob: 3\n", "lab13",
              "4", "defects_near_blob must be 0..hot_pixels + stuck_pixels");
  ExpectError("virtual:\n  sensor:\n    near_blob_radius_px: 0.5\n", "lab14", "3",
              "near_blob_radius_px must lie in [1, 200]");
  ExpectError("virtual:\n  sensor:\n    hot_pixels: 400\n    defects_near_blob: 300\n",
              "lab15", "4", "half the pixels within");
}

TEST(RigPhysics, MissingFileIsATypedError) {
  EXPECT_THROW(LoadRigPhysics("/nonexistent/rig.yaml"), RigFileError);
}

}  // namespace
}  // namespace irdist::sim
