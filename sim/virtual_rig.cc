#include "sim/virtual_rig.h"

#include <sstream>
#include <vector>

#include "base/bounds.h"
#include "base/yaml_fields.h"
#include "sim/camera_server.h"
#include "sim/station_emulator.h"

namespace irdist::sim {
namespace {

// One entry of the rig file's station.devices: (its other keys are its driver's).
struct DeviceEntry {
  std::string name, driver, port;
  YAML::Mark mark;
};

std::vector<DeviceEntry> ReadStationDevices(const std::string& rig_path, const std::string& text) {
  const YAML::Node root = yaml_fields::Parse(text, rig_path);
  const YAML::Node station = root.IsMap() ? root["station"] : YAML::Node();
  const YAML::Node devices = station && station.IsMap() ? station["devices"] : YAML::Node();
  std::vector<DeviceEntry> entries;
  if (!devices || devices.IsNull()) return entries;
  if (!devices.IsMap()) {
    yaml_fields::Fail(rig_path, devices.Mark(),
                      "station.devices must be a map of device name to its entry");
  }
  for (const auto& item : devices) {
    DeviceEntry entry;
    if (!item.first.IsScalar()) {
      yaml_fields::Fail(rig_path, item.first.Mark(),
                        "the keys of station.devices must be device names, not a list or a map");
    }
    entry.name = item.first.Scalar();
    entry.mark = item.second.Mark();
    if (!item.second.IsMap()) {
      yaml_fields::Fail(rig_path, entry.mark,
                        "station.devices." + entry.name + " must be a map (driver, port, ...)");
    }
    const std::string where = "station.devices." + entry.name;
    const auto required = [&](const char* key) {
      const YAML::Node value = item.second[key];
      if (!value) yaml_fields::Fail(rig_path, entry.mark, where + ": missing key '" + key + "'");
      return yaml_fields::AsString(value, rig_path, where + "." + key);
    };
    entry.driver = required("driver");
    entry.port = required("port");
    entries.push_back(entry);
  }
  return entries;
}

}  // namespace

bool VirtualRigOverrides::IsValid(std::string* why) const {
  if (time_scale && !bounds::kTimeScale.Contains(*time_scale)) {
    if (why) *why = "time_scale override must lie in [0.01, 1000]";
    return false;
  }
  if (serial && (serial->empty() || serial->size() >= 16)) {
    if (why) *why = "serial override must have 1..15 characters";
    return false;
  }
  if (trajectory_csv && trajectory_csv->empty()) {
    if (why) *why = "trajectory_csv override must name a file";
    return false;
  }
  return true;
}

std::string VirtualRigInfo::BriefReport() const {
  std::ostringstream out;
  out << "camera: " << camera_id << " at " << camera_address << " (serial " << serial << ")\n"
      << "station: " << (station_port.empty() ? "(none)" : station_port) << "\n";
  for (const auto& [name, port] : device_ports) out << "device " << name << ": " << port << "\n";
  out << "time_scale: " << time_scale << "\n";
  if (!trajectory_csv.empty()) out << "trajectory: " << trajectory_csv << "\n";
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
  return StartImpl(physics, rig_path, overrides);
}

std::unique_ptr<VirtualRig> VirtualRig::Start(const RigPhysics& physics,
                                              const std::string& rig_path) {
  return StartImpl(physics, rig_path, VirtualRigOverrides{});
}

std::unique_ptr<VirtualRig> VirtualRig::StartImpl(const RigPhysics& physics,
                                                  const std::string& rig_path,
                                                  const VirtualRigOverrides& overrides) {
  std::string why;
  IRDIST_CHECK(physics.IsValid(&why), why);
  std::unique_ptr<VirtualRig> rig(new VirtualRig(physics));
  if (overrides.trajectory_csv) {  // before the station powers up: its first rows are logged
    rig->world_->LogTrajectory(*overrides.trajectory_csv);
    rig->info_.trajectory_csv = *overrides.trajectory_csv;
  }
  rig->camera_ = std::make_unique<CameraServer>(*rig->world_, physics);
  rig->camera_->Start();
  rig->info_.camera_id = rig->camera_->device_id();
  rig->info_.camera_address = rig->camera_->address();
  rig->info_.serial = rig->camera_->serial();
  rig->info_.time_scale = physics.time_scale;
  rig->StartStation(rig_path, overrides.seed);
  return rig;
}

void VirtualRig::StartStation(const std::string& rig_path, std::optional<std::uint64_t> seed) {
  const std::string text = rig_path.empty() ? "" : yaml_fields::ReadFile(rig_path);
  const std::vector<DeviceEntry> devices =
      rig_path.empty() ? std::vector<DeviceEntry>{} : ReadStationDevices(rig_path, text);
  if (devices.empty()) {  // a single-box rig file: the irdist station
    EmulatorOptions options =
        rig_path.empty() ? EmulatorOptions{} : LoadEmulatorOptions(rig_path);
    if (seed) options.seed = *seed;
    station_ = std::make_unique<StationEmulator>(*world_, options);
    info_.station_port = station_->Start();
    return;
  }
  std::uint64_t device_seed = seed.value_or(physics_.sensor.seed);
  for (const DeviceEntry& entry : devices) {
    if (entry.port != "auto") continue;  // a real device on a real port
    const EmulatorInfo* emulator = FindEmulator(entry.driver);
    if (emulator == nullptr) {
      yaml_fields::Fail(rig_path, entry.mark,
                        "station.devices." + entry.name + ": no emulator for driver '" +
                            entry.driver + "' (docs/virtual-rig.md lists the emulated " +
                            "drivers); give the device's real port instead of auto");
    }
    const EmulatorSpec spec{entry.name, entry.driver, rig_path, text, ++device_seed};
    std::unique_ptr<DeviceEmulator> device = emulator->create(*world_, spec);
    info_.device_ports[entry.name] = device->Start();
    devices_[entry.name] = std::move(device);
  }
}

DeviceEmulator* VirtualRig::device(const std::string& name) {
  const auto it = devices_.find(name);
  return it == devices_.end() ? nullptr : it->second.get();
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
  for (auto& [name, device] : devices_) device->Stop();
  if (camera_) camera_->Stop();
}

}  // namespace irdist::sim
