#pragma once
// The whole virtual rig: one World, served as a GigE Vision camera on 127.0.0.1 (CameraServer)
// and as a motion station on pseudo-terminals: the irdist station (StationEmulator) for rig files
// without `station.devices:`, else one device emulator (sim/device_emulator.h) per
// `station.devices.<name>` whose port is `auto`, all acting on the one World. `irdist sim`, and
// calibrate/validate on a virtual rig, start one of these and connect to what Info() prints, as
// they would to hardware.

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>

#include "sim/device_emulator.h"
#include "sim/renderer.h"
#include "sim/rig_physics.h"
#include "sim/world.h"

namespace irdist::sim {

class CameraServer;
class StationEmulator;

// Values that replace the rig file's (unset = keep the file's).
struct VirtualRigOverrides {
  std::optional<double> time_scale;    // simulated s per host s
  std::optional<std::uint64_t> seed;   // sensor noise (and emulator) seed
  std::optional<std::string> serial;   // camera serial number (< 16 characters)
  // A new file the station's trajectory is logged to from the start (sim/trajectory_file.h;
  // `irdist sim` puts it in its state folder). Unset: not logged (the World keeps it anyway).
  std::optional<std::string> trajectory_csv;
  bool IsValid(std::string* why) const;
};

// What to connect to.
struct VirtualRigInfo {
  std::string camera_id;       // Aravis device id, "Aravis-Fake-<serial>"
  std::string camera_address;  // "127.0.0.1": open by address (loopback, docs/virtual-rig.md)
  std::string serial;          // verify it after opening the camera
  std::string station_port;    // irdist station's pty slave path, e.g. /dev/pts/7 (rig files
                               // without station.devices:; else empty)
  // station.devices.<name> -> its emulator's pty slave path (devices whose port is `auto`).
  std::map<std::string, std::string> device_ports;
  double time_scale = 1.0;
  std::string trajectory_csv;  // the trajectory file, when logged (else empty)
  std::string BriefReport() const;  // "camera: ...\nstation: ...\n[device <name>: ...\n]"
};

class VirtualRig {
 public:
  // Loads the rig file's `virtual:` section (physics and virtual.station:), applies the
  // overrides and starts the camera and the station. Throws RigFileError, CameraServerError,
  // TrajectoryFileError or irdist::Error (pty).
  static std::unique_ptr<VirtualRig> Start(const std::string& rig_path,
                                           const VirtualRigOverrides& overrides = {});
  // The same from already loaded physics (station options from `rig_path` if not empty).
  static std::unique_ptr<VirtualRig> Start(const RigPhysics& physics,
                                           const std::string& rig_path = "");
  ~VirtualRig();  // stops
  VirtualRig(const VirtualRig&) = delete;
  VirtualRig& operator=(const VirtualRig&) = delete;

  const VirtualRigInfo& Info() const { return info_; }
  World& world() { return *world_; }
  CameraServer& camera() { return *camera_; }
  StationEmulator* station() { return station_.get(); }  // nullptr with station.devices:
  // The emulator of station.devices.<name> (nullptr when that device has no emulator running).
  DeviceEmulator* device(const std::string& name);
  const RigPhysics& physics() const { return physics_; }

  // Noise-free ground truth of the scene for a pose, current and exposure (cold emitter unless
  // junction_rise_k is given), in the given output format.
  GroundTruth Describe(double slide_mm, double pan_deg, double tilt_deg, double bias_ma,
                       double exposure_us, PixelFormat format = PixelFormat::kMono12,
                       double junction_rise_k = 0.0) const;

  // Stops station and camera. Idempotent.
  void Stop();

 private:
  explicit VirtualRig(const RigPhysics& physics);
  static std::unique_ptr<VirtualRig> StartImpl(const RigPhysics& physics,
                                               const std::string& rig_path,
                                               const VirtualRigOverrides& overrides);

  RigPhysics physics_;
  std::unique_ptr<World> world_;
  std::unique_ptr<CameraServer> camera_;
  void StartStation(const std::string& rig_path, std::optional<std::uint64_t> seed);

  std::unique_ptr<StationEmulator> station_;
  std::map<std::string, std::unique_ptr<DeviceEmulator>> devices_;
  Renderer renderer_;
  VirtualRigInfo info_;
};

}  // namespace irdist::sim
