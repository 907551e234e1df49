#pragma once
// The camera alone, for the commands without a station sweep (measure, snap, view): the rig file's
// camera opened and configured. On a virtual rig with an `irdist sim` of the same rig file running
// (app/inputs/rig_lookup.h FindRunningSim), its camera is used as a bench camera: fired by software
// trigger, the IRED placed by `irdist station` (`--at` is refused). Otherwise on a virtual rig the
// rig itself is started first (and stopped at the end), its camera fired through the rig's trigger
// line, and `--at` places the IRED through the virtual station (the station protocol, as a sweep
// does). On hardware the camera is fired by software trigger.

#include <functional>
#include <iosfwd>
#include <memory>
#include <string>
#include <vector>

#include "app/inputs/rig.h"

namespace irdist {

class Camera;
struct CameraIdentity;

struct LiveCameraOptions {
  std::string rig_spec = "virtual";  // rig name or file
  double time_scale = 0.0;           // virtual rig: simulated s per host s (0 = rig file's)
  std::vector<double> at;            // SLIDE_MM, PAN_DEG, TILT_DEG, BIAS_MA (own virtual rig only)
  double first_exposure_us = 8000.0;
  double longest_exposure_us = 8000.0;  // sizes the frame timeout
  int buffer_count = 16;
  bool quiet = false;
  // The first problem, naming the field, in *why (empty when valid): the virtual rig's time scale
  // (0.01-1000, or 0), --at's four values (a current >= 0), positive exposures (the longest at
  // least the first; the camera refuses one outside its own range, naming the flag), 1-1000
  // stream buffers.
  bool IsValid(std::string* why) const;
};

class LiveCamera {
 public:
  // Throws UsageError (options not IsValid), RecipeError (rig file, --at on hardware), UsageError
  // (--at with a running sim),
  // CameraError, StationError, LinkError.
  LiveCamera(const LiveCameraOptions& options, std::ostream& err);
  ~LiveCamera();
  LiveCamera(const LiveCamera&) = delete;
  LiveCamera& operator=(const LiveCamera&) = delete;

  const Rig& rig() const;
  const std::string& rig_path() const;
  Camera& camera();
  // Fires one frame (the argument is BracketCapture's frame_in_bracket, -1 for a warm-up).
  std::function<void(int)> Trigger();
  std::string trigger_source() const;  // the camera's TriggerSource as configured
  int frame_timeout_ms() const;
  int bit_depth() const;
  // The camera's region: the whole sensor (true) or the rig's roi_px (false, as opened). Stops
  // the stream and configures the camera again; the next capture starts it (its frames are then
  // of the new size). For aiming (`irdist view`'s w key). Throws CameraError.
  void SetWholeSensor(bool whole);
  bool whole_sensor() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace irdist
