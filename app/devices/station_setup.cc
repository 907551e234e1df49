#include "app/devices/station_setup.h"

#include "app/inputs/errors.h"

namespace irdist {
namespace {

// The virtual rig exposes one pty per device emulator as VirtualRigInfo::device_ports (sim/
// adds it with the device emulators); until it exists, only the irdist station's pty is known.
template <typename Info>
auto DevicePortsOf(const Info& info, int) -> decltype(info.device_ports) {
  return info.device_ports;
}
template <typename Info>
std::map<std::string, std::string> DevicePortsOf(const Info&, long) {
  return {};
}

}  // namespace

std::map<std::string, std::string> VirtualDevicePorts(const Rig& rig,
                                                      const sim::VirtualRigInfo& info) {
  std::map<std::string, std::string> ports = DevicePortsOf(info, 0);
  for (const DeviceSpec& d : rig.station.composition.devices) {
    if (d.driver == "irdist_station" && ports.count(d.name) == 0 && !info.station_port.empty()) {
      ports[d.name] = info.station_port;
    }
  }
  return ports;
}

std::map<std::string, std::string> PortsOfRunningSim(const RunningSim& sim) {
  std::map<std::string, std::string> ports;
  for (const auto& [key, value] : sim.values) {
    if (key.rfind("port.", 0) == 0) ports[key.substr(5)] = value;
  }
  const auto single_box = sim.values.find("station_port");
  if (ports.empty() && single_box != sim.values.end()) {
    ports[kSingleBoxStationDevice] = single_box->second;
  }
  return ports;
}

std::map<std::string, std::string> ParsePortOverrides(const Rig& rig,
                                                      const std::vector<std::string>& args) {
  std::map<std::string, std::string> ports;
  for (const std::string& arg : args) {
    const std::size_t eq = arg.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == arg.size()) {
      throw UsageError("--port takes NAME=PATH (e.g. --port slide=/dev/ttyUSB0), not '" + arg +
                       "'");
    }
    const std::string name = arg.substr(0, eq);
    if (rig.station.composition.Find(name) == nullptr) {
      throw UsageError("--port " + arg + ": the rig " + rig.path + " has no station device '" +
                       name + "'" +
                       (rig.station.composed ? "" : " (a single-box rig's device is 'station')"));
    }
    ports[name] = arg.substr(eq + 1);
  }
  return ports;
}

StationOptions StationRunOptions(const std::map<std::string, std::string>& ports, LineLog* log) {
  StationOptions options;
  options.ports = ports;
  options.log = log;
  return options;
}

std::string RigTriggerSource(const Rig& rig) {
  const StationSpec& spec = rig.station.composition;
  if (rig.kind == RigKind::kVirtual && spec.trigger != kCameraSoftwareTrigger) return "Line1";
  return rig.camera.trigger_source;
}

}  // namespace irdist
