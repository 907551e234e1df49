#pragma once
// Rig files (recipes/rigs/*.yaml): which camera and which station a run uses. The app reads the
// `camera:` and `station:` sections into plain structs; the `virtual:` section (physics of the
// virtual rig) is accepted here and parsed by sim/ itself. docs/recipes.md lists every key.

#include <iosfwd>
#include <string>
#include <vector>

#include "station/plan.h"
#include "station/station.h"

namespace irdist {

// The smallest region of interest a rig may set (features take a 64 px window around the blob).
constexpr int kMinRoiSidePx = 96;

// The camera's intrinsics in OpenCV's convention (cv::calibrateCamera): focal lengths and
// principal point in pixels (pixel centres at whole coordinates), distortion k1 k2 p1 p2 k3.
// `pixels: sensor` (the full sensor's pixels) or `pixels: roi` (the region's own pixels, as a
// calibration on ROI images gives them). docs/recipes.md says how to obtain them.
struct CameraIntrinsics {
  bool known = false;  // the rig file has `camera.intrinsics`
  bool in_roi_px = false;
  double fx_px = 0.0, fy_px = 0.0, cx_px = 0.0, cy_px = 0.0;
  std::vector<double> distortion;  // k1, k2, p1, p2, k3 (trailing ones may be left out)
};

struct CameraConfig {
  std::string id = "auto";               // Aravis device id, serial or IP; "auto" = the only one
  std::string pixel_format = "Mono12";   // Mono8, Mono10(p), Mono12(p), Mono12Packed or Mono16
  std::string trigger_source = "Line1";  // camera input wired to the station's trigger output
  std::string trigger_activation = "RisingEdge";  // RisingEdge or FallingEdge
  int black_level = 0;                            // camera black level register, >= 0
  int packet_size = 0;                            // GigE Vision packet size, bytes; 0 = negotiate
  int frame_timeout_ms = 1000;  // a frame later than this after its trigger is lost
  double readout_ms = 25.0;     // sensor readout + transfer of one frame (plan estimate)
  // `trigger_in_readout: true` = the camera takes a trigger while it reads the previous frame out
  // (GenICam TriggerOverlap ReadOut, or a camera that queues it): brackets trigger each frame
  // during its predecessor's readout. false (the default) = trigger after the frame arrived. The
  // old spelling `trigger_overlap: readout | off` is still read, with a note (Rig::notes).
  bool trigger_in_readout = false;
  // `exposure_check: chunk | readback | none` (absent or `auto`: the chunk where the camera
  // declares it and its frames carry it, else the read-back, said once; acquisition/camera.h).
  std::string exposure_check = "auto";
  // `restore_after: true` (the default): calibrate, validate, measure, snap and view put back
  // every feature irdist changed when they end, whether done, failed or interrupted; false
  // leaves the camera as irdist set it (for a next run on the same settings).
  bool restore_after = true;
  // Region of interest `roi_px: [offset_x, offset_y, width, height]` (sensor pixels); width 0 =
  // the full sensor. A region around the IRED's image cuts each frame's transfer, the recording
  // and the host's work by the ratio of areas (docs/recipes.md).
  int roi_offset_x = 0;
  int roi_offset_y = 0;
  int roi_width = 0;
  int roi_height = 0;
  bool FullFrame() const { return roi_width == 0; }
  // Optional `intrinsics:`: with them measure and validate report the 3D position.
  CameraIntrinsics intrinsics;
  bool IsValid(std::string* why) const;
};

// A closed interval [min, max] in the axis's unit.
struct AxisRange {
  double min = 0.0;
  double max = 0.0;
  bool Contains(double value) const { return value >= min && value <= max; }
};

// The station's soft limits: a recipe value outside them is an error before anything moves.
struct StationLimits {
  AxisRange slide_mm{1000.0, 3500.0};
  AxisRange pan_deg{-45.0, 45.0};
  AxisRange tilt_deg{-45.0, 45.0};
  AxisRange bias_ma{0.0, 600.0};
  bool IsValid(std::string* why) const;
};

// The `station:` section. Two spellings:
// - single-box (one irdist station box): `port`, `baud`, `reply_timeout_ms`, `limits`, `motion`;
//   it means one irdist_station device named "station" filling every role;
// - composed: `roles: {motion: [names], source: name, trigger: camera_software | name}`,
//   `devices: {<name>: {driver, port, baud, reply_timeout_ms, axes: {slide|pan|tilt: address},
//   ...driver keys}}`, `current_tolerance_ma`, `limits`, `motion`.
// Either way `composition` holds the devices and roles the run opens (station/station.h).
struct StationConfig {
  // The single-box spelling only (one irdist station box).
  std::string port = "auto";   // serial device (/dev/ttyUSB0); "auto": the virtual rig's pty
  int baud = 115200;           // serial speed, bit/s
  int reply_timeout_ms = 500;  // deadline of every reply
  StationLimits limits;
  MotionModel motion;  // optional `motion:` section; readout_ms comes from camera:
  StationSpec composition;
  bool composed = false;  // true when written with roles/devices
  // Optional `emitter_offset_mm: [x, y, z]`: the emitter's centre from the crossing of the pan and
  // tilt axes (which the slide carries along the optical axis), in the mount's frame at pan =
  // tilt = 0 (x right and y down as the camera sees it, z away from the camera). Ground truth
  // turns it with the pan and tilt (app/processing/position.h TrueGeometryOf). Hardware rigs only.
  double emitter_offset_mm[3] = {0.0, 0.0, 0.0};
  bool IsValid(std::string* why) const;
};

// The name of the single device a single-box `station:` section stands for.
constexpr const char* kSingleBoxStationDevice = "station";


enum class RigKind { kVirtual, kHardware };

struct Rig {
  std::string path;  // the file it was read from
  std::string name;  // `name:`, defaults to the file's stem
  RigKind kind = RigKind::kVirtual;
  CameraConfig camera;
  StationConfig station;
  // `track: {accel_psd_mm2_per_s3: Q}`: `measure --track`'s filter process noise (mm^2/s^3,
  // estimator/track_filter.h; --accel-psd overrides it); 0 = the filter's default.
  double track_accel_psd_mm2_per_s3 = 0.0;
  bool has_virtual_section = false;
  // What the file still says in an old spelling, each "file:line: what, and the new spelling";
  // read as before. The commands print them (PrintRigNotes).
  std::vector<std::string> notes;
  bool IsValid(std::string* why) const;
};

// Prints each of rig.notes as "note: ..." to `err`.
void PrintRigNotes(const Rig& rig, std::ostream& err);

// Reads and checks a rig file. Throws RecipeError (file:line:column and what would be valid) on an
// unreadable file, unknown key, wrong type or inconsistent value.
Rig LoadRig(const std::string& path);
// Same, from text; `file` names it in errors.
Rig ParseRig(const std::string& text, const std::string& file);

// Plan-time check of the trigger against the camera: camera_software needs
// camera.trigger_source Software; a device's trigger line needs a Line source. Throws RecipeError
// naming the rig file and the fix.
void CheckTriggerSettings(const Rig& rig);

}  // namespace irdist
