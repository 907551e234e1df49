#include "app/inputs/rig.h"

#include <gtest/gtest.h>

#include <exception>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>

#include "app/inputs/errors.h"
#include "sim/rig_physics.h"

namespace irdist {
namespace {

const std::string kRigs = std::string(IRDIST_SOURCE_DIR) + "/recipes/rigs";

TEST(RigTest, DefaultsAreValid) {
  std::string why;
  EXPECT_TRUE(CameraConfig().IsValid(&why)) << why;
  EXPECT_TRUE(StationLimits().IsValid(&why)) << why;
  EXPECT_TRUE(StationConfig().IsValid(&why)) << why;
  EXPECT_TRUE(Rig().IsValid(&why)) << why;
}

TEST(RigTest, VirtualRigLoads) {
  const Rig rig = LoadRig(kRigs + "/virtual.yaml");
  EXPECT_EQ(rig.name, "virtual");
  EXPECT_EQ(rig.kind, RigKind::kVirtual);
  EXPECT_EQ(rig.camera.trigger_source, "Line1");
  EXPECT_EQ(rig.station.limits.slide_mm.min, 1000.0);
  EXPECT_EQ(rig.station.limits.slide_mm.max, 3500.0);
  EXPECT_EQ(rig.station.limits.pan_deg.min, -45.0);
  EXPECT_EQ(rig.station.limits.bias_ma.max, 600.0);
  // A region around the sensor's centre, where the virtual IRED images at every pose.
  EXPECT_EQ(rig.camera.roi_offset_x + rig.camera.roi_width / 2, 640);
  EXPECT_EQ(rig.camera.roi_offset_y + rig.camera.roi_height / 2, 512);
  std::string why;
  EXPECT_TRUE(rig.IsValid(&why)) << why;
}

// The duration estimate and physical bound of a virtual rig use the rig file's camera.readout_ms;
// the virtual camera reads out after virtual.camera.readout_ms. They must agree, or `irdist plan`
// and bench/sweep measure against a wrong bound.
TEST(RigTest, VirtualRigsEstimateWithTheirCamerasOwnReadout) {
  for (const char* name : {"virtual.yaml", "virtual-cosm.yaml"}) {
    const Rig rig = LoadRig(kRigs + "/" + name);
    const sim::RigPhysics physics = sim::LoadRigPhysics(kRigs + "/" + name);
    EXPECT_DOUBLE_EQ(rig.camera.readout_ms, physics.camera.readout_ms) << name;
    EXPECT_DOUBLE_EQ(rig.station.motion.readout_ms, physics.camera.readout_ms) << name;
  }
}

// The virtual rigs' intrinsics are those of their physics: f / pitch, the sensor's centre in
// OpenCV's convention (pixel centres at whole numbers), no distortion.
TEST(RigTest, VirtualRigsCarryTheIntrinsicsOfTheirPhysics) {
  for (const char* name : {"virtual.yaml", "virtual-cosm.yaml", "virtual-offset.yaml"}) {
    const Rig rig = LoadRig(kRigs + "/" + name);
    const sim::RigPhysics physics = sim::LoadRigPhysics(kRigs + "/" + name);
    const CameraIntrinsics& k = rig.camera.intrinsics;
    ASSERT_TRUE(k.known) << name;
    EXPECT_FALSE(k.in_roi_px) << name;
    const double f_px = physics.optics.focal_length_mm / (physics.sensor.pixel_pitch_um * 1e-3);
    EXPECT_NEAR(k.fx_px, f_px, 1e-5) << name;
    EXPECT_NEAR(k.fy_px, f_px, 1e-5) << name;
    EXPECT_DOUBLE_EQ(k.cx_px, 0.5 * physics.sensor.width_px - 0.5) << name;
    EXPECT_DOUBLE_EQ(k.cy_px, 0.5 * physics.sensor.height_px - 0.5) << name;
    for (double c : k.distortion) EXPECT_EQ(c, 0.0) << name;
  }
}

TEST(RigTest, IntrinsicsNeedTheirKeysAndRefuseUnknownOnes) {
  const std::string head =
      "name: r\nkind: hardware\nstation:\n  port: /dev/ttyUSB0\ncamera:\n  id: 10.0.0.2\n"
      "  intrinsics:\n";
  const Rig rig = ParseRig(head + "    pixels: roi\n    fx: 2000\n    fy: 2001\n    cx: 127.5\n"
                                  "    cy: 120\n    distortion: [-0.1, 0.01]\n",
                           "r.yaml");
  EXPECT_TRUE(rig.camera.intrinsics.in_roi_px);
  EXPECT_EQ(rig.camera.intrinsics.fy_px, 2001.0);
  EXPECT_EQ(rig.camera.intrinsics.distortion, (std::vector<double>{-0.1, 0.01}));
  EXPECT_THROW(ParseRig(head + "    fx: 2000\n    fy: 2000\n    cx: 1\n", "r.yaml"), RecipeError);
  EXPECT_THROW(ParseRig(head + "    fx: 2000\n    fy: 2000\n    cx: 1\n    cy: 1\n    k1: 0\n",
                        "r.yaml"),
               RecipeError);
  EXPECT_THROW(ParseRig(head + "    fx: -1\n    fy: 2000\n    cx: 1\n    cy: 1\n", "r.yaml"),
               RecipeError);
  EXPECT_FALSE(LoadRig(kRigs + "/example-hardware.yaml").camera.intrinsics.known);
}

// The refusal of ParseRig(text), or "" when it accepts.
std::string RefusalOf(const std::string& text) {
  try {
    ParseRig(text, "r.yaml");
  } catch (const RecipeError& e) {
    return e.what();
  }
  return "";
}

// Regression: out-of-range intrinsics gave wrong distances marked ok (distortion 1e10 gave
// 2015.7 mm for 2000; cx 1e300 and fx 1e-300 dropped the position). Each is refused at its
// line and column with the range; the rest of the intrinsics as before.
TEST(RigTest, IntrinsicsOutsideTheirPhysicalBoundsAreRefused) {
  const std::string head =
      "name: r\nkind: hardware\nstation:\n  port: /dev/ttyUSB0\ncamera:\n  id: 10.0.0.2\n"
      "  roi_px: [512, 384, 256, 256]\n  intrinsics:\n    pixels: sensor\n";
  const std::string focal = "    fx: 3000\n    fy: 3000\n";
  const std::string centre = "    cx: 639.5\n    cy: 511.5\n";
  EXPECT_EQ(RefusalOf(head + focal + centre + "    distortion: [-0.2, 0.05, 0.001, 0, 0.1]\n"), "");
  const struct {
    std::string text;
    std::string expected;
  } cases[] = {
      {focal + centre + "    distortion: [1e10, 0, 0, 0, 0]\n",
       "r.yaml:14:18: camera.intrinsics.distortion[0] = 1e+10 is outside [-5, 5]"},
      {focal + centre + "    distortion: [-1e6, 0, 0, 0, 0]\n", "distortion[0] = -1000000"},
      {focal + centre + "    distortion: [0, 0, 0.5, 0, 0]\n", "distortion[2] = 0.5 is outside"},
      {focal + "    cx: 1e300\n    cy: 511.5\n", "r.yaml:12:9: camera.intrinsics.cx = 1e+300"},
      {"    fx: 1e-300\n    fy: 3000\n" + centre, "camera.intrinsics.fx = 1e-300 is outside "
                                                     "[10, 1000000] px"},
      {"    fx: 30\n    fy: 30\n" + centre + "    distortion: [-4, 0, 0, 0, 0]\n",
       "moves the ROI's farthest corner by"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.text);
    EXPECT_NE(RefusalOf(head + c.text).find(c.expected), std::string::npos)
        << RefusalOf(head + c.text);
  }
}

// Regression: intrinsics in sensor pixels stated as `pixels: roi` gave theta 14 deg for 10;
// the principal point must lie inside the pixels it is stated in.
TEST(RigTest, APrincipalPointOutsideTheRoiItIsStatedInIsRefused) {
  const std::string head =
      "name: r\nkind: hardware\nstation:\n  port: /dev/ttyUSB0\ncamera:\n  id: 10.0.0.2\n"
      "  roi_px: [512, 384, 256, 256]\n  intrinsics:\n    pixels: roi\n    fx: 3000\n"
      "    fy: 3000\n";
  EXPECT_EQ(RefusalOf(head + "    cx: 127.5\n    cy: 127.5\n"), "");
  const std::string refusal = RefusalOf(head + "    cx: 639.5\n    cy: 511.5\n");
  EXPECT_NE(refusal.find("r.yaml:12:"), std::string::npos) << refusal;
  EXPECT_NE(refusal.find("outside the 256 x 256 px ROI"), std::string::npos) << refusal;
  EXPECT_NE(refusal.find("pixels: sensor"), std::string::npos) << refusal;
}

// The rig's delays (readout, settling, overheads) lie within a day: 1e308 ms overflowed the plan's
// sums; each is refused at its line with the range.
TEST(RigTest, DelaysBeyondADayAreRefused) {
  const std::string head = "name: r\nkind: hardware\ncamera:\n  id: 10.0.0.2\n";
  const std::string station = "station:\n  port: /dev/ttyUSB0\n";
  EXPECT_EQ(RefusalOf(head + "  readout_ms: 86400000\n" + station), "");
  EXPECT_NE(RefusalOf(head + "  readout_ms: 1e308\n" + station)
                .find("r.yaml:5:15: camera.readout_ms = 1e+308 is outside [0, 86400000] ms"),
            std::string::npos)
      << RefusalOf(head + "  readout_ms: 1e308\n" + station);
  EXPECT_NE(RefusalOf(head + station + "  motion:\n    slide: {settle_ms: -1}\n")
                .find("settle_ms = -1 is outside"),
            std::string::npos);
  EXPECT_NE(RefusalOf(head + station + "  motion:\n    pose_overhead_ms: 1e300\n")
                .find("pose_overhead_ms = 1e+300 is outside"),
            std::string::npos);
}

// measure --track's process noise as a rig key: read, bounded, unknown keys refused.
TEST(RigTest, TrackAccelPsdIsReadAndBounded) {
  const std::string head = "name: r\nkind: hardware\ncamera:\n  id: 10.0.0.2\n";
  const std::string station = "station:\n  port: /dev/ttyUSB0\n";
  EXPECT_EQ(ParseRig(head + station, "r.yaml").track_accel_psd_mm2_per_s3, 0.0);
  EXPECT_EQ(ParseRig(head + station + "track:\n  accel_psd_mm2_per_s3: 2.5e4\n", "r.yaml")
                .track_accel_psd_mm2_per_s3,
            2.5e4);
  EXPECT_NE(RefusalOf(head + station + "track:\n  accel_psd_mm2_per_s3: -1\n")
                .find("r.yaml:8:25: track.accel_psd_mm2_per_s3 = -1 is outside"),
            std::string::npos)
      << RefusalOf(head + station + "track:\n  accel_psd_mm2_per_s3: -1\n");
  EXPECT_NE(RefusalOf(head + station + "track:\n  accel_psd: 1e5\n").find("accel_psd"),
            std::string::npos);
}

TEST(RigTest, EmitterOffsetIsThreeFiniteNumbersOnAHardwareRig) {
  const std::string head = "name: r\nkind: hardware\ncamera:\n  id: 10.0.0.2\nstation:\n  port: "
                           "/dev/ttyUSB0\n  emitter_offset_mm: ";
  const Rig rig = ParseRig(head + "[5, 0, -80]\n", "r.yaml");
  EXPECT_EQ(rig.station.emitter_offset_mm[0], 5.0);
  EXPECT_EQ(rig.station.emitter_offset_mm[2], -80.0);
  EXPECT_EQ(LoadRig(kRigs + "/example-hardware.yaml").station.emitter_offset_mm[2], 0.0);
  EXPECT_THROW(ParseRig(head + "[5, 0]\n", "r.yaml"), RecipeError);
  EXPECT_THROW(ParseRig(head + "[5, 0, .nan]\n", "r.yaml"), RecipeError);
  // A virtual rig's emitter is placed by its physics (virtual.emitter.offset_*), not this key.
  std::string text;
  {
    std::ifstream in(kRigs + "/virtual.yaml");
    text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  const size_t at = text.find("  baud: 115200");
  ASSERT_NE(at, std::string::npos);
  text.insert(at, "  emitter_offset_mm: [0, 0, 10]\n");
  EXPECT_THROW(ParseRig(text, "v.yaml"), RecipeError);
}

TEST(RigTest, ExampleHardwareRigLoads) {
  const Rig rig = LoadRig(kRigs + "/example-hardware.yaml");
  EXPECT_EQ(rig.kind, RigKind::kHardware);
  EXPECT_EQ(rig.station.port, "/dev/ttyUSB0");
  EXPECT_FALSE(rig.has_virtual_section);
  EXPECT_EQ(rig.station.motion.slide.speed, 50.0);
  EXPECT_EQ(rig.station.motion.pan.acceleration, 20.0);
  EXPECT_EQ(rig.station.motion.readout_ms, rig.camera.readout_ms);
  EXPECT_TRUE(rig.camera.FullFrame());  // no roi_px: the whole sensor until the user sets one
}

// Every rig file the project ships loads, each device's settings checked by its driver: a user
// copies one of them to start (example-lab.yaml once lacked the slide's step size its driver
// requires, and the first command on a real rig refused it).
TEST(RigTest, EveryShippedRigLoads) {
  int rigs = 0;
  for (const auto& entry : std::filesystem::directory_iterator(kRigs)) {
    if (entry.path().extension() != ".yaml") continue;
    ++rigs;
    try {
      LoadRig(entry.path().string());
    } catch (const std::exception& e) {
      ADD_FAILURE() << e.what();  // names the file, its line and the fix
    }
  }
  EXPECT_GE(rigs, 10);
}

// Packed formats (PFNC Mono10p / Mono12p, GigE Vision Mono12Packed) are accepted as such.
TEST(RigTest, PackedPixelFormatsAreAccepted) {
  for (const char* format : {"Mono10p", "Mono12p", "Mono12Packed"}) {
    const Rig rig = ParseRig(std::string("kind: virtual\ncamera:\n  pixel_format: ") + format +
                                 "\n",
                             "packed.yaml");
    EXPECT_EQ(rig.camera.pixel_format, format);
  }
}

// A hardware rig's file for EveryKeyIsRead: its camera's and station's keys set, each to be read
// back (the pan's acceleration left to its default).
constexpr char kEveryKeyRig[] = R"(name: lab
kind: hardware
camera:
  id: "192.168.1.20"
  pixel_format: Mono16
  trigger_source: Line2
  trigger_activation: FallingEdge
  black_level: 12
  packet_size: 8000
  frame_timeout_ms: 2500
  readout_ms: 40
  roi_px: [300, 200, 320, 240]
station:
  port: /dev/ttyACM0
  baud: 9600
  reply_timeout_ms: 800
  limits:
    slide_mm: [1200, 3000]
    pan_deg: [-30, 30]
    tilt_deg: [-10, 10]
    bias_ma: [100, 550]
  motion:
    slide: {speed: 80, acceleration: 100, settle_ms: 300}
    pan: {speed: 10}
    axes_move_together: false
    frame_overhead_ms: 7
    pose_overhead_ms: 90
)";

TEST(RigTest, EveryKeyIsRead) {
  const Rig rig = ParseRig(kEveryKeyRig, "lab.yaml");
  EXPECT_EQ(rig.name, "lab");
  EXPECT_EQ(rig.camera.id, "192.168.1.20");
  EXPECT_EQ(rig.camera.pixel_format, "Mono16");
  EXPECT_EQ(rig.camera.trigger_source, "Line2");
  EXPECT_EQ(rig.camera.trigger_activation, "FallingEdge");
  EXPECT_EQ(rig.camera.black_level, 12);
  EXPECT_EQ(rig.camera.packet_size, 8000);
  EXPECT_EQ(rig.camera.frame_timeout_ms, 2500);
  EXPECT_FALSE(rig.camera.FullFrame());
  EXPECT_EQ(rig.camera.roi_offset_x, 300);
  EXPECT_EQ(rig.camera.roi_offset_y, 200);
  EXPECT_EQ(rig.camera.roi_width, 320);
  EXPECT_EQ(rig.camera.roi_height, 240);
  EXPECT_EQ(rig.station.port, "/dev/ttyACM0");
  EXPECT_EQ(rig.station.baud, 9600);
  EXPECT_EQ(rig.station.reply_timeout_ms, 800);
  EXPECT_EQ(rig.station.limits.slide_mm.min, 1200.0);
  EXPECT_EQ(rig.station.limits.tilt_deg.max, 10.0);
  EXPECT_EQ(rig.station.limits.bias_ma.min, 100.0);
  const MotionModel& m = rig.station.motion;
  EXPECT_EQ(m.slide.speed, 80.0);
  EXPECT_EQ(m.slide.acceleration, 100.0);
  EXPECT_EQ(m.slide.settle_ms, 300.0);
  EXPECT_EQ(m.pan.speed, 10.0);
  EXPECT_EQ(m.pan.acceleration, MotionModel().pan.acceleration);  // unspecified: default
  EXPECT_FALSE(m.axes_move_together);
  EXPECT_EQ(m.frame_overhead_ms, 7.0);
  EXPECT_EQ(m.pose_overhead_ms, 90.0);
  EXPECT_EQ(m.readout_ms, 40.0);
}

struct BadRig {
  const char* what;
  const char* text;
  int line;
  int column;
  const char* message;
};

const BadRig kBadRigs[] = {
    {"unknown camera key", "kind: virtual\ncamera:\n  exposure: 3\n", 3, 3,
     "unknown key 'exposure' in camera"},
    {"unknown top-level key", "kind: virtual\ncameras: {}\n", 2, 1, "did you mean 'camera'?"},
    {"wrong type", "kind: virtual\nstation:\n  baud: fast\n", 3, 9, "must be a whole number"},
    {"limits min above max", "kind: virtual\nstation:\n  limits:\n    pan_deg: [45, -45]\n", 4, 14,
     "must have min < max"},
    {"limits not a pair", "kind: virtual\nstation:\n  limits:\n    pan_deg: 45\n", 4, 14,
     "a list [min, max]"},
    {"bad pixel format", "kind: virtual\ncamera:\n  pixel_format: RGB8\n", 3, 17,
     "valid: Mono8, Mono10, Mono10p, Mono12, Mono12p, Mono12Packed, Mono16"},
    {"bad kind", "kind: imaginary\n", 1, 7, "valid: virtual, hardware"},
    {"hardware with an automatic port", "kind: hardware\nstation:\n  port: auto\n", 3, 9,
     "must name the serial device"},
    {"roi not four numbers", "kind: virtual\ncamera:\n  roi_px: [0, 0, 256]\n", 3, 11,
     "must be [offset_x, offset_y, width, height]"},
    {"roi negative offset", "kind: virtual\ncamera:\n  roi_px: [-8, 0, 256, 256]\n", 3, 12,
     "whole number >= 0"},
    {"roi too small", "kind: virtual\ncamera:\n  roi_px: [0, 0, 64, 256]\n", 3, 11,
     "width and height must be >= 96"},
    {"negative speed", "kind: virtual\nstation:\n  motion:\n    tilt: {speed: -1}\n", 4, 19,
     "speed must be > 0"},
    // Huge numbers: refused before any cast or sum could overflow.
    {"roi beyond any sensor", "kind: virtual\ncamera:\n  roi_px: [1e300, 0, 256, 256]\n", 3, 12,
     "at most 1048576"},
    {"limits beyond any station", "kind: virtual\nstation:\n  limits:\n    slide_mm: [0, 1e308]\n",
     4, 15, "must lie within [-1000000, 1000000]"},
    {"baud beyond any tty", "kind: virtual\nstation:\n  baud: 2000000000\n", 3, 9,
     "1..4000000 bit/s"},
    {"integer out of range", "kind: virtual\ncamera:\n  black_level: 2147483647\n", 3, 16,
     "black_level '2147483647' is out of range"},
    // A device key that is a list: was yaml-cpp's own "bad conversion", naming no file.
    {"device name that is a list",
     "kind: virtual\nstation:\n  roles: {motion: box, source: box, trigger: box}\n  devices:\n"
     "    [a, b]: {driver: irdist_station, port: auto}\n",
     5, 5, "the keys of station.devices must be names"},
    {"device key that is a map",
     "kind: virtual\nstation:\n  roles: {motion: box, source: box, trigger: box}\n  devices:\n"
     "    box: {driver: irdist_station, port: auto, {a: 1}: 2}\n",
     5, 47, "station.devices.box keys must be names"},
};

TEST(RigTest, BadRigFilesNameTheirLineAndColumn) {
  for (const BadRig& bad : kBadRigs) {
    SCOPED_TRACE(bad.what);
    try {
      ParseRig(bad.text, "rig.yaml");
      ADD_FAILURE() << "no error";
    } catch (const RecipeError& e) {
      EXPECT_EQ(e.File(), "rig.yaml");
      EXPECT_EQ(e.Line(), bad.line) << e.what();
      EXPECT_EQ(e.Column(), bad.column) << e.what();
      EXPECT_NE(e.Message().find(bad.message), std::string::npos) << e.what();
    }
  }
}

// One name for triggering during readout: camera.trigger_in_readout. The old spelling
// `trigger_overlap: readout | off` still reads the same, with a note naming the file and line and
// the new spelling; both at once are refused; the shipped rigs use the new name.
TEST(RigTest, TriggerInReadoutAndItsOldSpellingWithANote) {
  const Rig now = ParseRig("kind: virtual\ncamera:\n  trigger_in_readout: true\n", "r.yaml");
  EXPECT_TRUE(now.camera.trigger_in_readout);
  EXPECT_TRUE(now.notes.empty());
  EXPECT_FALSE(ParseRig("kind: virtual\ncamera: {}\n", "r.yaml").camera.trigger_in_readout);
  for (const bool readout : {true, false}) {
    const Rig old = ParseRig(std::string("kind: virtual\ncamera:\n  id: x\n  trigger_overlap: ") +
                                 (readout ? "readout" : "off") + "\n",
                             "old.yaml");
    EXPECT_EQ(old.camera.trigger_in_readout, readout);
    ASSERT_EQ(old.notes.size(), 1u);
    EXPECT_EQ(old.notes[0].rfind("old.yaml:4: camera.trigger_overlap is the old name", 0), 0u)
        << old.notes[0];
    EXPECT_NE(old.notes[0].find(std::string("trigger_in_readout: ") + (readout ? "true" : "false")),
              std::string::npos)
        << old.notes[0];
    std::ostringstream err;
    PrintRigNotes(old, err);
    EXPECT_EQ(err.str(), "note: " + old.notes[0] + "\n");
  }
  EXPECT_NE(RefusalOf("kind: virtual\ncamera:\n  trigger_overlap: readout\n"
                      "  trigger_in_readout: true\n")
                .find("r.yaml:3:20: camera.trigger_overlap is the old name"),
            std::string::npos);
  EXPECT_NE(RefusalOf("kind: virtual\ncamera:\n  trigger_overlap: sometimes\n").find("sometimes"),
            std::string::npos);
  for (const char* name : {"virtual", "virtual-lab", "virtual-offset", "example-hardware"}) {
    EXPECT_TRUE(LoadRig(kRigs + "/" + name + ".yaml").notes.empty()) << name;
  }
  EXPECT_TRUE(LoadRig(kRigs + "/virtual.yaml").camera.trigger_in_readout);
}

// camera.exposure_check: the chunk, the read-back or none; absent = auto; anything else refused at
// its line with the choices.
TEST(RigTest, ExposureCheckIsOneOfItsChoices) {
  EXPECT_EQ(ParseRig("kind: virtual\ncamera: {id: auto}\n", "rig.yaml").camera.exposure_check, "auto");
  for (const std::string choice : {"chunk", "readback", "none", "auto"}) {
    EXPECT_EQ(ParseRig("kind: virtual\ncamera:\n  exposure_check: " + choice + "\n",
                       "rig.yaml")
                  .camera.exposure_check,
              choice);
  }
  try {
    ParseRig("kind: virtual\ncamera:\n  id: auto\n  exposure_check: chunks\n", "rig.yaml");
    ADD_FAILURE() << "no error";
  } catch (const RecipeError& e) {
    EXPECT_EQ(e.Line(), 4) << e.what();
    EXPECT_NE(e.Message().find("readback"), std::string::npos) << e.what();
  }
}

// camera.restore_after: true by default (the camera put back when a command ends), false kept.
TEST(RigTest, RestoreAfterIsTrueUnlessSaidOtherwise) {
  EXPECT_TRUE(ParseRig("kind: virtual\ncamera: {id: auto}\n", "rig.yaml").camera.restore_after);
  EXPECT_FALSE(ParseRig("kind: virtual\ncamera:\n  restore_after: false\n", "rig.yaml")
                   .camera.restore_after);
  EXPECT_THROW(ParseRig("kind: virtual\ncamera:\n  restore_after: later\n", "rig.yaml"),
               RecipeError);
}

TEST(RigTest, MissingRigFileIsARecipeError) {
  EXPECT_THROW(LoadRig("/nonexistent/rig.yaml"), RecipeError);
}

// A single-box `station: {port, baud, ...}` is one irdist_station device filling every role.
TEST(RigTest, ASingleBoxStationIsOneIrdistStationInEveryRole) {
  const Rig rig = LoadRig(kRigs + "/example-hardware.yaml");
  const StationSpec& spec = rig.station.composition;
  ASSERT_EQ(spec.devices.size(), 1u);
  EXPECT_EQ(spec.devices[0].name, "station");
  EXPECT_EQ(spec.devices[0].driver, "irdist_station");
  EXPECT_EQ(spec.devices[0].port, "/dev/ttyUSB0");
  EXPECT_EQ(spec.devices[0].baud, 115200);
  EXPECT_EQ(spec.motion, (std::vector<std::string>{"station"}));
  EXPECT_EQ(spec.source, "station");
  EXPECT_EQ(spec.trigger, "station");
  EXPECT_FALSE(rig.station.composed);
}

constexpr const char* kComposed = R"(name: lab
kind: hardware
camera:
  id: "192.168.1.20"
  trigger_source: Line1
station:
  current_tolerance_ma: 2.5
  roles:
    motion: [box]
    source: box
    trigger: box
  devices:
    box:
      driver: irdist_station
      port: /dev/ttyUSB3
      baud: 57600
      trigger_width_us: 200
)";

TEST(RigTest, AComposedStationIsReadStrictly) {
  const Rig rig = ParseRig(kComposed, "lab.yaml");
  const StationSpec& spec = rig.station.composition;
  EXPECT_TRUE(rig.station.composed);
  ASSERT_EQ(spec.devices.size(), 1u);
  EXPECT_EQ(spec.devices[0].port, "/dev/ttyUSB3");
  EXPECT_EQ(spec.devices[0].baud, 57600);
  EXPECT_EQ(spec.devices[0].settings.at("trigger_width_us").text, "200");
  EXPECT_EQ(spec.devices[0].settings.at("trigger_width_us").line, 17);
  EXPECT_DOUBLE_EQ(spec.current_tolerance_ma, 2.5);
}

TEST(RigTest, AMisspeltDriverKeyIsAnErrorWithItsLine) {
  std::string text = kComposed;
  text.replace(text.find("trigger_width_us"), 16, "trigger_widht_us");
  try {
    ParseRig(text, "lab.yaml");
    ADD_FAILURE() << "no error";
  } catch (const RecipeError& e) {
    EXPECT_EQ(e.Line(), 17) << e.what();
    EXPECT_NE(e.Message().find("trigger_width_us"), std::string::npos) << e.what();
  }
}

TEST(RigTest, ARoleNamingNoDeviceIsAnError) {
  std::string text = kComposed;
  text.replace(text.find("source: box"), 11, "source: bx");
  EXPECT_THROW(ParseRig(text, "lab.yaml"), RecipeError);
}

// Trigger settings are checked when the rig is loaded (plan time), with the fix.
TEST(RigTest, TheTriggerMustMatchTheCamerasTriggerSource) {
  std::string text = kComposed;
  text.replace(text.find("trigger_source: Line1"), 21, "trigger_source: Software");
  try {
    ParseRig(text, "lab.yaml");
    ADD_FAILURE() << "no error";
  } catch (const RecipeError& e) {
    EXPECT_NE(e.Message().find("Line1"), std::string::npos) << e.what();
  }
  text = kComposed;
  text.replace(text.find("trigger: box"), 12, "trigger: camera_software");
  try {
    ParseRig(text, "lab.yaml");
    ADD_FAILURE() << "no error";
  } catch (const RecipeError& e) {
    EXPECT_NE(e.Message().find("trigger_source: Software"), std::string::npos) << e.what();
  }
}

// A composed lab: a Zaber stage and a source meter. `motion` and `source` are replaced below.
std::string TwoDeviceRig(const std::string& motion, const std::string& slide_axes) {
  return "kind: hardware\ncamera:\n  trigger_source: Software\nstation:\n  roles:\n"
         "    motion: " + motion + "\n    source: meter\n    trigger: camera_software\n"
         "  devices:\n    stage:\n      driver: zaber_ascii\n      port: /dev/ttyUSB0\n"
         "      axes: " + slide_axes + "\n      fullstep_um: 6.35\n      fullstep_deg: 0.1\n"
         "    meter:\n      driver: scpi_source\n      port: /dev/ttyUSB1\n"
         "      compliance_v: 3\n";
}

// Roles and axes are checked when the rig is read (plan time), naming the rig file's line: a
// source meter cannot move; an axis needs exactly one device (was station.cc's internal checks,
// and "axis driven by 2 devices" without the file's name, at run time).
TEST(RigTest, RolesDevicesCannotFillAndAxesWithoutOneDeviceNameTheRigFile) {
  const std::string axes = "{slide: \"1 1\", pan: \"2 1\", tilt: \"3 1\"}";
  EXPECT_NO_THROW(ParseRig(TwoDeviceRig("stage", axes), "lab.yaml"));
  try {
    ParseRig(TwoDeviceRig("[stage, meter]", axes), "lab.yaml");
    ADD_FAILURE() << "a source meter accepted as a motion device";
  } catch (const RecipeError& e) {
    EXPECT_EQ(e.File(), "lab.yaml");
    EXPECT_EQ(e.Line(), 17) << e.what();  // the meter's entry
    EXPECT_NE(e.Message().find("station.roles.motion names device 'meter' (driver scpi_source), "
                               "which cannot fill the motion role; name one that can: stage"),
              std::string::npos)
        << e.what();
  }
  try {
    ParseRig(TwoDeviceRig("stage", "{slide: \"1 1\", pan: \"2 1\"}"), "lab.yaml");
    ADD_FAILURE() << "a rig without a tilt axis accepted";
  } catch (const RecipeError& e) {
    EXPECT_EQ(e.File(), "lab.yaml");
    EXPECT_NE(e.Message().find("axis tilt is driven by 0 motion devices"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace irdist
