#include "app/inputs/rig.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <ostream>
#include <vector>

#include "app/inputs/errors.h"
#include "base/bounds.h"
#include "base/yaml_fields.h"
#include "station/serial_transport.h"

namespace irdist {
namespace {

using yaml_fields::AsBounded;
using yaml_fields::AsNumber;
using yaml_fields::Fail;
using yaml_fields::MapReader;

// station.limits beyond this (1 km, a million degrees or mA) are typos, and would overflow the
// station's centi-unit counts.
constexpr double kMaxLimitMagnitude = 1e6;
constexpr double kMaxSensorPx = 1 << 20;  // no sensor is wider

bool Fail(std::string* why, const std::string& message) {
  if (why != nullptr) *why = message;
  return false;
}

void OneOf(const MapReader& map, const std::string& key, const std::string& value,
           const std::vector<std::string>& valid) {
  if (std::find(valid.begin(), valid.end(), value) == valid.end()) {
    Fail(map.File(), map.Get(key).Mark(),
         key + " '" + value + "' is not supported; valid: " + yaml_fields::JoinNames(valid));
  }
}

int AtLeast(const MapReader& map, const std::string& key, int fallback, int minimum) {
  const int value = map.Integer(key, fallback);
  if (value < minimum) {
    Fail(map.File(), map.Get(key).Mark(),
         key + " must be >= " + std::to_string(minimum) + ", not " + std::to_string(value));
  }
  return value;
}

// A delay or wait in ms: within a day (bounds::kDelayMs; 1e308 would overflow the plan's sums).
double DelayMs(const MapReader& map, const std::string& key, double fallback) {
  return map.Bounded(key, fallback, bounds::kDelayMs);
}

double Positive(const MapReader& map, const std::string& key, double fallback) {
  const double value = map.Number(key, fallback);
  if (!(value > 0.0)) Fail(map.File(), map.Get(key).Mark(), key + " must be > 0");
  return value;
}

// camera.intrinsics: {pixels: sensor|roi, fx, fy, cx, cy, distortion: [k1, k2, p1, p2, k3]}, each
// inside its physical bound (base/bounds.h); CheckIntrinsicsAgainstPixels the cross-checks.
CameraIntrinsics ReadIntrinsics(const YAML::Node& node, const std::string& file) {
  const MapReader map(node, file, "camera.intrinsics",
                      {"pixels", "fx", "fy", "cx", "cy", "distortion"});
  CameraIntrinsics k;
  k.known = true;
  const std::string pixels = map.String("pixels", "sensor");
  OneOf(map, "pixels", pixels, {"sensor", "roi"});
  k.in_roi_px = pixels == "roi";
  const std::string fix = "give the lens's calibration (OpenCV's calibrateCamera)";
  k.fx_px = AsBounded(map.Require("fx"), file, "camera.intrinsics.fx", bounds::kFocalPx, fix);
  k.fy_px = AsBounded(map.Require("fy"), file, "camera.intrinsics.fy", bounds::kFocalPx, fix);
  k.cx_px = AsBounded(map.Require("cx"), file, "camera.intrinsics.cx", bounds::kSensorPx, fix);
  k.cy_px = AsBounded(map.Require("cy"), file, "camera.intrinsics.cy", bounds::kSensorPx, fix);
  if (map.Has("distortion")) {
    const YAML::Node d = map.Get("distortion");
    if (!d.IsSequence() || d.size() > 5) {
      Fail(file, d.Mark(), "camera.intrinsics.distortion must be [k1, k2, p1, p2, k3] (OpenCV's "
                           "order; up to 5 numbers)");
    }
    for (size_t i = 0; i < d.size(); ++i) {
      const bool tangential = i == 2 || i == 3;
      k.distortion.push_back(AsBounded(
          d[i], file, "camera.intrinsics.distortion[" + std::to_string(i) + "]",
          tangential ? bounds::kTangentialDistortion : bounds::kRadialDistortion, fix));
    }
  }
  return k;
}

// The intrinsics against the pixels they are stated in: the principal point inside them (the
// ROI's with `pixels: roi`), and the distortion moving the ROI's farthest corner by less than
// bounds::kMaxCornerDistortion of its radius.
void CheckIntrinsicsAgainstPixels(const CameraConfig& camera, const YAML::Node& node,
                                  const std::string& file) {
  const CameraIntrinsics& k = camera.intrinsics;
  const bool roi = camera.roi_width > 0;
  if (k.in_roi_px && roi && !(k.cx_px <= camera.roi_width && k.cy_px <= camera.roi_height)) {
    Fail(file, node["cx"].Mark(),
         "camera.intrinsics (pixels: roi): the principal point (" + BoundNumber(k.cx_px) + ", " +
             BoundNumber(k.cy_px) + ") lies outside the " + std::to_string(camera.roi_width) +
             " x " + std::to_string(camera.roi_height) + " px ROI it is stated in; give cx, cy in "
             "the ROI's pixels (sensor value - roi offset) or set pixels: sensor");
  }
  if (!roi) return;  // the sensor's size is the camera's: the corner is unknown here
  const double x0 = k.in_roi_px ? 0.0 : camera.roi_offset_x;
  const double y0 = k.in_roi_px ? 0.0 : camera.roi_offset_y;
  const double dx = std::max(std::fabs(x0 - k.cx_px), std::fabs(x0 + camera.roi_width - k.cx_px));
  const double dy = std::max(std::fabs(y0 - k.cy_px), std::fabs(y0 + camera.roi_height - k.cy_px));
  const double r2 = (dx / k.fx_px) * (dx / k.fx_px) + (dy / k.fy_px) * (dy / k.fy_px);
  double radial = 0.0, power = r2;
  for (size_t i : {size_t{0}, size_t{1}, size_t{4}}) {
    if (i < k.distortion.size()) radial += k.distortion[i] * power;
    power *= r2;
  }
  if (!(std::fabs(radial) <= bounds::kMaxCornerDistortion)) {
    Fail(file, node["distortion"].Mark(),
         "camera.intrinsics.distortion moves the ROI's farthest corner by " +
             BoundNumber(100.0 * radial) + "% of its radius (at most " +
             BoundNumber(100.0 * bounds::kMaxCornerDistortion) + "%: a measurement lens, not a "
             "fisheye); check k1, k2, k3 and the units of fx, fy");
  }
}

// camera.trigger_in_readout, or its old spelling `trigger_overlap: readout | off` with a note.
bool ReadTriggerInReadout(const MapReader& map, std::vector<std::string>* notes) {
  if (!map.Has("trigger_overlap")) return map.Boolean("trigger_in_readout", false);
  const YAML::Node old = map.Get("trigger_overlap");
  if (map.Has("trigger_in_readout")) {
    Fail(map.File(), old.Mark(),
         "camera.trigger_overlap is the old name of camera.trigger_in_readout; keep only "
         "trigger_in_readout");
  }
  const std::string overlap = map.String("trigger_overlap", "off");
  OneOf(map, "trigger_overlap", overlap, {"off", "readout"});
  const bool in_readout = overlap == "readout";
  notes->push_back(map.File() + ":" + std::to_string(old.Mark().line + 1) +
                   ": camera.trigger_overlap is the old name of camera.trigger_in_readout (read "
                   "as before); write `trigger_in_readout: " + (in_readout ? "true" : "false") +
                   "` instead");
  return in_readout;
}

CameraConfig ReadCamera(const YAML::Node& node, const std::string& file,
                        std::vector<std::string>* notes) {
  const MapReader map(node, file, "camera",
                      {"id", "pixel_format", "trigger_source", "trigger_activation", "black_level",
                       "packet_size", "frame_timeout_ms", "readout_ms", "trigger_in_readout",
                       "trigger_overlap", "roi_px", "intrinsics", "exposure_check",
                       "restore_after"});
  CameraConfig camera;
  camera.id = map.String("id", camera.id);
  camera.pixel_format = map.String("pixel_format", camera.pixel_format);
  OneOf(map, "pixel_format", camera.pixel_format,
        {"Mono8", "Mono10", "Mono10p", "Mono12", "Mono12p", "Mono12Packed", "Mono16"});
  camera.trigger_source = map.String("trigger_source", camera.trigger_source);
  camera.trigger_activation = map.String("trigger_activation", camera.trigger_activation);
  OneOf(map, "trigger_activation", camera.trigger_activation, {"RisingEdge", "FallingEdge"});
  camera.black_level = AtLeast(map, "black_level", camera.black_level, 0);
  camera.packet_size = AtLeast(map, "packet_size", camera.packet_size, 0);
  camera.frame_timeout_ms = AtLeast(map, "frame_timeout_ms", camera.frame_timeout_ms, 1);
  camera.readout_ms = DelayMs(map, "readout_ms", camera.readout_ms);
  camera.trigger_in_readout = ReadTriggerInReadout(map, notes);
  camera.exposure_check = map.String("exposure_check", camera.exposure_check);
  OneOf(map, "exposure_check", camera.exposure_check, {"auto", "chunk", "readback", "none"});
  camera.restore_after = map.Boolean("restore_after", camera.restore_after);
  if (map.Has("roi_px")) {
    const YAML::Node node = map.Get("roi_px");
    const std::string shape =
        "camera.roi_px must be [offset_x, offset_y, width, height] in sensor pixels (or absent "
        "for the full sensor)";
    if (!node.IsSequence() || node.size() != 4) Fail(file, node.Mark(), shape);
    int v[4];
    for (int i = 0; i < 4; ++i) {
      const double x = AsNumber(node[i], file, "camera.roi_px");
      // Range first: casting 1e300 to int is undefined behaviour.
      if (!(x >= 0.0 && x <= kMaxSensorPx) || x != std::floor(x)) {
        Fail(file, node[i].Mark(), shape + "; every value a whole number >= 0 (at most 1048576)");
      }
      v[i] = static_cast<int>(x);
    }
    if (v[2] < kMinRoiSidePx || v[3] < kMinRoiSidePx) {
      Fail(file, node.Mark(),
           "camera.roi_px: width and height must be >= " + std::to_string(kMinRoiSidePx) +
               " px (the features' 64 px window around the IRED's image, with a margin); widen "
               "the region");
    }
    camera.roi_offset_x = v[0];
    camera.roi_offset_y = v[1];
    camera.roi_width = v[2];
    camera.roi_height = v[3];
  }
  if (map.Has("intrinsics")) {
    camera.intrinsics = ReadIntrinsics(map.Get("intrinsics"), file);
    CheckIntrinsicsAgainstPixels(camera, map.Get("intrinsics"), file);
  }
  return camera;
}

AxisRange ReadRange(const MapReader& limits, const std::string& key, AxisRange fallback) {
  if (!limits.Has(key)) return fallback;
  const YAML::Node node = limits.Get(key);
  if (!node.IsSequence() || node.size() != 2) {
    Fail(limits.File(), node.Mark(),
         "station.limits." + key + " must be a list [min, max] of two numbers");
  }
  AxisRange range{AsNumber(node[0], limits.File(), key + " min"),
                  AsNumber(node[1], limits.File(), key + " max")};
  if (!(range.min < range.max)) {
    Fail(limits.File(), node.Mark(), "station.limits." + key + " must have min < max");
  }
  if (!(std::abs(range.min) <= kMaxLimitMagnitude && std::abs(range.max) <= kMaxLimitMagnitude)) {
    Fail(limits.File(), node.Mark(),
         "station.limits." + key + " must lie within [-1000000, 1000000] (mm, deg or mA); give "
         "the station's real travel");
  }
  return range;
}

AxisMotion ReadAxisMotion(const MapReader& motion, const std::string& key, AxisMotion fallback) {
  if (!motion.Has(key)) return fallback;
  const MapReader map(motion.Get(key), motion.File(), "station.motion." + key,
                      {"speed", "acceleration", "settle_ms", "home"});
  AxisMotion axis;
  axis.speed = Positive(map, "speed", fallback.speed);
  axis.acceleration = Positive(map, "acceleration", fallback.acceleration);
  axis.settle_ms = DelayMs(map, "settle_ms", fallback.settle_ms);
  axis.home = map.Has("home") ? map.Number("home", fallback.home) : fallback.home;
  return axis;
}

StationLimits ReadLimits(const MapReader& map, StationLimits limits_in) {
  if (!map.Has("limits")) return limits_in;
  const MapReader limits(map.Get("limits"), map.File(), "station.limits",
                         {"slide_mm", "pan_deg", "tilt_deg", "bias_ma"});
  StationLimits out;
  out.slide_mm = ReadRange(limits, "slide_mm", limits_in.slide_mm);
  out.pan_deg = ReadRange(limits, "pan_deg", limits_in.pan_deg);
  out.tilt_deg = ReadRange(limits, "tilt_deg", limits_in.tilt_deg);
  out.bias_ma = ReadRange(limits, "bias_ma", limits_in.bias_ma);
  return out;
}

MotionModel ReadMotionModel(const MapReader& map, MotionModel model) {
  if (!map.Has("motion")) return model;
  const MapReader motion(
      map.Get("motion"), map.File(), "station.motion",
      {"slide", "pan", "tilt", "axes_move_together", "frame_overhead_ms", "pose_overhead_ms"});
  model.slide = ReadAxisMotion(motion, "slide", model.slide);
  model.pan = ReadAxisMotion(motion, "pan", model.pan);
  model.tilt = ReadAxisMotion(motion, "tilt", model.tilt);
  model.axes_move_together = motion.Boolean("axes_move_together", model.axes_move_together);
  model.frame_overhead_ms = DelayMs(motion, "frame_overhead_ms", model.frame_overhead_ms);
  model.pose_overhead_ms = DelayMs(motion, "pose_overhead_ms", model.pose_overhead_ms);
  return model;
}

// A single-box `station: {port, baud, reply_timeout_ms}` is one irdist station filling every role.
StationSpec SingleBoxComposition(const StationConfig& station, const std::string& file, int line) {
  StationSpec spec;
  DeviceSpec device;
  device.name = kSingleBoxStationDevice;
  device.driver = "irdist_station";
  device.port = station.port;
  device.baud = station.baud;
  device.reply_timeout_ms = station.reply_timeout_ms;
  device.file = file;
  device.line = line;
  spec.devices.push_back(device);
  spec.motion = {device.name};
  spec.source = device.name;
  spec.trigger = device.name;
  return spec;
}

std::map<Axis, std::string> ReadAxes(const YAML::Node& node, const std::string& file,
                                     const std::string& context) {
  const MapReader map(node, file, context, {"slide", "pan", "tilt"});
  std::map<Axis, std::string> axes;
  for (Axis axis : {Axis::kSlide, Axis::kPan, Axis::kTilt}) {
    if (map.Has(AxisName(axis))) {
      axes[axis] = yaml_fields::AsString(map.Get(AxisName(axis)), file, context);
    }
  }
  return axes;
}

// A key of station.devices (a device's name) or of one device's entry: a name, never a list or
// a map (yaml-cpp would throw its own "bad conversion", naming no file).
std::string DeviceKey(const YAML::Node& key, const std::string& file, const std::string& what) {
  if (!key.IsScalar() || key.Scalar().empty()) {
    Fail(file, key.Mark(),
         what + " must be names (e.g. slide:, source:), not " +
             (key.IsSequence() ? "a list" : key.IsMap() ? "a map" : "an empty key"));
  }
  return key.Scalar();
}

// One `station.devices.<name>:` entry; the driver's own keys are checked by its validate().
DeviceSpec ReadDevice(const std::string& name, const YAML::Node& node, const std::string& file) {
  const std::string context = "station.devices." + name;
  if (!node.IsMap()) Fail(file, node.Mark(), context + " must be a map (driver, port, ...)");
  DeviceSpec device;
  device.name = name;
  device.file = file;
  device.line = node.Mark().line + 1;
  for (const auto& entry : node) {
    const std::string key = DeviceKey(entry.first, file, context + " keys");
    const YAML::Node& value = entry.second;
    const std::string what = context + "." + key;
    if (key == "driver") {
      device.driver = yaml_fields::AsString(value, file, what);
    } else if (key == "port") {
      device.port = yaml_fields::AsString(value, file, what);
    } else if (key == "baud") {
      device.baud = yaml_fields::AsInteger(value, file, what);
      if (device.baud < 0 || device.baud > static_cast<int>(kMaxBaud)) {
        Fail(file, value.Mark(),
             what + " must lie in 0..4000000 bit/s (e.g. 9600, 115200; 0: the driver's default)");
      }
    } else if (key == "reply_timeout_ms") {
      device.reply_timeout_ms = yaml_fields::AsInteger(value, file, what);
    } else if (key == "axes") {
      device.axes = ReadAxes(value, file, what);
    } else {
      if (!value.IsScalar()) Fail(file, value.Mark(), what + " must be a single value");
      device.settings[key] = {value.Scalar(), value.Mark().line + 1};
    }
  }
  const DriverInfo* info = FindDriver(device.driver);
  if (info == nullptr) {
    Fail(file, node.Mark(),
         context + ".driver '" + device.driver + "' is not a known driver; valid: " +
             yaml_fields::JoinNames(DriverNames()));
  }
  if (device.baud < 0 || device.reply_timeout_ms < 0) {
    Fail(file, node.Mark(), context + ": baud and reply_timeout_ms must be > 0");
  }
  if (info->validate) info->validate(device);
  return device;
}

std::string DeviceName(const YAML::Node& node, const StationSpec& spec, const std::string& file,
                       const std::string& role) {
  const std::string name = yaml_fields::AsString(node, file, "station.roles." + role);
  if (spec.Find(name) == nullptr && !(role == "trigger" && name == kCameraSoftwareTrigger)) {
    std::vector<std::string> names;
    for (const DeviceSpec& d : spec.devices) names.push_back(d.name);
    Fail(file, node.Mark(),
         "station.roles." + role + " names '" + name + "', which is not in station.devices (" +
             yaml_fields::JoinNames(names) + ")" +
             (role == "trigger" ? std::string(" nor camera_software") : std::string()));
  }
  return name;
}

void ReadRoles(const YAML::Node& node, const std::string& file, StationSpec* spec) {
  const MapReader roles(node, file, "station.roles", {"motion", "source", "trigger"});
  const YAML::Node motion = roles.Require("motion");
  if (motion.IsSequence()) {
    for (const YAML::Node& m : motion) spec->motion.push_back(DeviceName(m, *spec, file, "motion"));
  } else {
    spec->motion.push_back(DeviceName(motion, *spec, file, "motion"));
  }
  spec->source = DeviceName(roles.Require("source"), *spec, file, "source");
  spec->trigger = DeviceName(roles.Require("trigger"), *spec, file, "trigger");
}

StationSpec ReadComposition(const MapReader& map) {
  StationSpec spec;
  const YAML::Node devices = map.Require("devices");
  if (!devices.IsMap() || devices.size() == 0) {
    Fail(map.File(), devices.Mark(), "station.devices must map device names to their entries");
  }
  for (const auto& entry : devices) {
    const std::string name = DeviceKey(entry.first, map.File(), "the keys of station.devices");
    if (spec.Find(name) != nullptr) {
      Fail(map.File(), entry.first.Mark(), "station.devices names '" + name + "' twice");
    }
    spec.devices.push_back(ReadDevice(name, entry.second, map.File()));
  }
  ReadRoles(map.Require("roles"), map.File(), &spec);
  CheckStationRoles(spec);
  spec.current_tolerance_ma =
      Positive(map, "current_tolerance_ma", spec.current_tolerance_ma);
  return spec;
}

// `station.emitter_offset_mm: [x, y, z]` (finite mm), when given.
void ReadEmitterOffset(const MapReader& map, double offset_mm[3]) {
  if (!map.Has("emitter_offset_mm")) return;
  const YAML::Node node = map.Get("emitter_offset_mm");
  if (!node.IsSequence() || node.size() != 3) {
    Fail(map.File(), node.Mark(),
         "station.emitter_offset_mm must be [x, y, z] in mm (the emitter's centre from the pan "
         "and tilt axes' crossing)");
  }
  for (int i = 0; i < 3; ++i) {
    offset_mm[i] = AsNumber(node[i], map.File(), "station.emitter_offset_mm[" +
                                                      std::to_string(i) + "]");
    if (!std::isfinite(offset_mm[i])) {
      Fail(map.File(), node[i].Mark(), "station.emitter_offset_mm must be finite numbers");
    }
  }
}

StationConfig ReadStation(const YAML::Node& node, const std::string& file) {
  const MapReader map(node, file, "station",
                      {"port", "baud", "reply_timeout_ms", "limits", "motion", "roles", "devices",
                       "current_tolerance_ma", "emitter_offset_mm"});
  StationConfig station;
  station.limits = ReadLimits(map, station.limits);
  ReadEmitterOffset(map, station.emitter_offset_mm);
  station.motion = ReadMotionModel(map, station.motion);
  station.composed = map.Has("roles") || map.Has("devices");
  if (station.composed) {
    for (const char* key : {"port", "baud", "reply_timeout_ms"}) {
      if (map.Has(key)) {
        Fail(file, map.Get(key).Mark(),
             std::string("station.") + key +
                 " belongs to a device under station.devices when roles/devices are used");
      }
    }
    station.composition = ReadComposition(map);
    return station;
  }
  station.port = map.String("port", station.port);
  station.baud = AtLeast(map, "baud", station.baud, 1);
  if (station.baud > static_cast<int>(kMaxBaud)) {
    Fail(file, map.Get("baud").Mark(), "station.baud must lie in 1..4000000 bit/s (e.g. 115200)");
  }
  station.reply_timeout_ms = AtLeast(map, "reply_timeout_ms", station.reply_timeout_ms, 1);
  station.composition = SingleBoxComposition(station, file, map.Mark().line + 1);
  station.composition.current_tolerance_ma =
      Positive(map, "current_tolerance_ma", station.composition.current_tolerance_ma);
  return station;
}

void CheckHardwarePorts(const Rig& rig, const MapReader& map) {
  if (!rig.station.composed && rig.station.port == "auto") {
    const YAML::Node station = map.Get("station");
    const YAML::Node port = station ? station["port"] : YAML::Node();
    Fail(rig.path, port ? port.Mark() : map.Mark(),
         "station.port must name the serial device on a hardware rig (e.g. /dev/ttyUSB0), "
         "not auto");
  }
  for (const DeviceSpec& d : rig.station.composition.devices) {
    if (d.port == "auto") {
      throw RecipeError(rig.path, d.line, 0,
                        "station.devices." + d.name +
                            ".port must name the serial device on a hardware rig (e.g. "
                            "/dev/ttyUSB0), not auto");
    }
  }
}

}  // namespace

void CheckTriggerSettings(const Rig& rig) {
  const std::string& trigger = rig.station.composition.trigger;
  const std::string& source = rig.camera.trigger_source;
  if (trigger == kCameraSoftwareTrigger) {
    if (source != "Software") {
      throw RecipeError(rig.path, 0, 0,
                        "station.roles.trigger is camera_software but camera.trigger_source is '" +
                            source + "'; set camera.trigger_source: Software");
    }
    return;
  }
  const DeviceSpec* device = rig.station.composition.Find(trigger);
  if (device != nullptr && device->driver == "irdist_station") {
    if (source.rfind("Line", 0) != 0) {
      throw RecipeError(rig.path, device->line, 0,
                        "the trigger is the irdist station's output (device '" + trigger +
                            "'), wired to a camera input line, but camera.trigger_source is '" +
                            source + "'; set it to the line it is wired to (e.g. Line1), or use "
                            "station.roles.trigger: camera_software with trigger_source: "
                            "Software");
    }
    return;
  }
  throw RecipeError(rig.path, device != nullptr ? device->line : 0, 0,
                    "station.roles.trigger '" + trigger +
                        "' cannot trigger the camera; use camera_software (with "
                        "camera.trigger_source: Software) or an irdist_station device wired to a "
                        "camera line (camera.trigger_source: Line1)");
}

bool CameraConfig::IsValid(std::string* why) const {
  if (id.empty()) return Fail(why, "camera.id must not be empty (use auto)");
  if (black_level < 0) return Fail(why, "camera.black_level must be >= 0");
  if (packet_size < 0) return Fail(why, "camera.packet_size must be >= 0");
  if (frame_timeout_ms < 1) return Fail(why, "camera.frame_timeout_ms must be >= 1");
  if (!(readout_ms >= 0.0)) return Fail(why, "camera.readout_ms must be >= 0");
  if (roi_offset_x < 0 || roi_offset_y < 0 || roi_width < 0 || roi_height < 0) {
    return Fail(why, "camera.roi_px values must be >= 0");
  }
  if (!FullFrame() && (roi_width < kMinRoiSidePx || roi_height < kMinRoiSidePx)) {
    return Fail(why, "camera.roi_px: width and height must be >= " +
                         std::to_string(kMinRoiSidePx) + " px");
  }
  return true;
}

bool StationLimits::IsValid(std::string* why) const {
  for (const AxisRange* range : {&slide_mm, &pan_deg, &tilt_deg, &bias_ma}) {
    if (!(range->min < range->max)) return Fail(why, "station.limits: every min must be < max");
  }
  return true;
}

bool StationConfig::IsValid(std::string* why) const {
  for (const DeviceSpec& d : composition.devices) {
    if (d.port.empty()) return Fail(why, "station.devices." + d.name + ".port must not be empty");
  }
  if (!(composition.current_tolerance_ma > 0.0)) {
    return Fail(why, "station.current_tolerance_ma must be > 0");
  }
  if (composed) return limits.IsValid(why) && motion.IsValid(why);
  if (port.empty()) return Fail(why, "station.port must not be empty (use auto)");
  if (baud < 1) return Fail(why, "station.baud must be >= 1");
  if (reply_timeout_ms < 1) return Fail(why, "station.reply_timeout_ms must be >= 1");
  return limits.IsValid(why) && motion.IsValid(why);
}

bool Rig::IsValid(std::string* why) const { return camera.IsValid(why) && station.IsValid(why); }

Rig ParseRig(const std::string& text, const std::string& file) {
  const YAML::Node root = yaml_fields::Parse(text, file);
  const MapReader map(root, file, "the rig file",
                      {"name", "kind", "camera", "station", "track", "virtual"});
  Rig rig;
  rig.path = file;
  rig.name = map.String("name", std::filesystem::path(file).stem().string());
  const std::string kind = map.String("kind", "hardware");
  OneOf(map, "kind", kind, {"virtual", "hardware"});
  rig.kind = kind == "virtual" ? RigKind::kVirtual : RigKind::kHardware;
  if (map.Has("camera")) rig.camera = ReadCamera(map.Get("camera"), file, &rig.notes);
  if (map.Has("station")) {
    rig.station = ReadStation(map.Get("station"), file);
  } else {
    rig.station.composition = SingleBoxComposition(rig.station, file, 0);
  }
  rig.station.motion.readout_ms = rig.camera.readout_ms;
  if (map.Has("track")) {
    const MapReader track(map.Get("track"), file, "track", {"accel_psd_mm2_per_s3"});
    rig.track_accel_psd_mm2_per_s3 =
        track.Bounded("accel_psd_mm2_per_s3", 0.0, bounds::kAccelPsd, "accel_psd_mm2_per_s3: 1e5");
  }
  rig.has_virtual_section = map.Has("virtual");
  if (rig.kind == RigKind::kHardware) {
    if (rig.has_virtual_section) {
      Fail(file, map.Get("virtual").Mark(),
           "a virtual: section belongs to a rig of kind: virtual; remove it or set kind: virtual");
    }
    CheckHardwarePorts(rig, map);
  } else if (map.Has("station") && map.Get("station")["emitter_offset_mm"]) {
    Fail(file, map.Get("station")["emitter_offset_mm"].Mark(),
         "station.emitter_offset_mm is for hardware rigs; a virtual rig's emitter sits at "
         "virtual.emitter.offset_x_mm/offset_y_mm");
  }
  std::string why;
  if (!rig.IsValid(&why)) Fail(file, map.Mark(), why);
  CheckTriggerSettings(rig);
  return rig;
}

Rig LoadRig(const std::string& path) { return ParseRig(yaml_fields::ReadFile(path), path); }

void PrintRigNotes(const Rig& rig, std::ostream& err) {
  for (const std::string& note : rig.notes) err << "note: " << note << "\n";
}

}  // namespace irdist
