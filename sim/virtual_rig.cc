#include "sim/virtual_rig.h"

#include <sstream>

#include "sim/camera_server.h"
#include "sim/station_emulator.h"

namespace irdist::sim {

bool VirtualRigOverrides::IsValid(std::string* why) const {
  if (time_scale && !(*time_scale >= 0.01 && *time_scale <= 1000.0)) {
    if (why) *why = "time_scale override must lie in [0.01, 1000]";
    return false;
  }
  if (serial && (serial->empty() || serial->size() >= 16)) {
    if (why) *why = "serial override must have 1..15 characters";
    return false;
  }
  return true;
}

std::string VirtualRigInfo::BriefReport() const {
  std::ostringstream out;
  out << "camera: " << camera_id << " at " << camera_address << " (serial " << serial << ")\n"
      << "station: " << (station_port.empty() ? "(none)" : station_port) << "\n"
      << "time_scale: " << time_scale << "\n";
  return out.str();
}

VirtualRig::VirtualRig(const RigPhysics& physics)
    : physics_(physics),
      world_(std::make_unique<World>(physics.time_scale)),
      renderer_(physics) {}

VirtualRig::~VirtualRig() { Stop(); }

std::unique_ptr<VirtualRig> VirtualRig::Start(const std::string& rig_path,
                                              const VirtualRigOverrides& overrides) {
  std::string why;
  IRDIST_CHECK(overrides.IsValid(&why), why);
  RigPhysics physics = LoadRigPhysics(rig_path);
  if (overrides.time_scale) physics.time_scale = *overrides.time_scale;
  if (overrides.seed) physics.sensor.seed = *overrides.seed;
  if (overrides.serial) physics.camera.serial = *overrides.serial;
  return StartImpl(physics, rig_path, overrides.seed);
}

std::unique_ptr<VirtualRig> VirtualRig::Start(const RigPhysics& physics,
                                              const std::string& rig_path) {
  return StartImpl(physics, rig_path, std::nullopt);
}

std::unique_ptr<VirtualRig> VirtualRig::StartImpl(const RigPhysics& physics,
                                                  const std::string& rig_path,
                                                  std::optional<std::uint64_t> seed) {
  std::string why;
  IRDIST_CHECK(physics.IsValid(&why), why);
  std::unique_ptr<VirtualRig> rig(new VirtualRig(physics));
  rig->camera_ = std::make_unique<CameraServer>(*rig->world_, physics);
  rig->camera_->Start();
  rig->info_.camera_id = rig->camera_->device_id();
  rig->info_.camera_address = rig->camera_->address();
  rig->info_.serial = rig->camera_->serial();
  rig->info_.time_scale = physics.time_scale;
  EmulatorOptions options = rig_path.empty() ? EmulatorOptions{} : LoadEmulatorOptions(rig_path);
  if (seed) options.seed = *seed;
  rig->station_ = std::make_unique<StationEmulator>(*rig->world_, options);
  rig->info_.station_port = rig->station_->Start();
  return rig;
}

GroundTruth VirtualRig::Describe(double slide_mm, double pan_deg, double tilt_deg, double bias_ma,
                                 double exposure_us, PixelFormat format,
                                 double junction_rise_k) const {
  PoseState pose;
  pose.slide_mm = slide_mm;
  pose.pan_deg = pan_deg;
  pose.tilt_deg = tilt_deg;
  pose.bias_ma = bias_ma;
  return renderer_.Describe(pose, exposure_us * 1e-6, format, junction_rise_k);
}

void VirtualRig::Stop() {
  if (station_) station_->Stop();
  if (camera_) camera_->Stop();
}

}  // namespace irdist::sim
