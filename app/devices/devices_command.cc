#include "app/devices/devices_command.h"

#include <filesystem>
#include <ostream>
#include <string>
#include <vector>

#include "acquisition/aravis_camera.h"
#include "app/inputs/state_file.h"

namespace irdist {

namespace fs = std::filesystem;

void RunDevices(const DevicesArgs& args, CommandIo io) {
  io.out << "Virtual rigs (irdist sim):\n";
  int rigs = 0;
  for (const RunningSim& sim : LiveSims(io.err)) {
    const auto value = [&sim](const char* key) {
      const auto found = sim.values.find(key);
      return found == sim.values.end() ? std::string("?") : found->second;
    };
    ++rigs;
    io.out << "  pid " << sim.pid << ": camera " << value("camera_id") << " at "
           << value("camera_address") << " serial " << value("serial") << ", station "
           << value("station_port") << ", time scale " << value("time_scale") << "\n";
  }
  std::error_code error;
  if (rigs == 0) io.out << "  none\n";

  io.out << "Serial ports:\n";
  int ports = 0;
  for (const auto& entry : fs::directory_iterator("/dev", error)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("ttyUSB", 0) == 0 || name.rfind("ttyACM", 0) == 0) {
      io.out << "  " << entry.path().string() << "\n";
      ++ports;
    }
  }
  if (ports == 0) io.out << "  none\n";

  if (!args.discover) {
    io.out << "Cameras: not searched (discovery broadcasts on every network interface; add "
              "--discover)\n";
    return;
  }
  io.out << "Cameras:\n";
  const std::vector<DeviceInfo> cameras = ListCameras();
  for (const DeviceInfo& d : cameras) {
    io.out << "  " << d.id << " (" << d.protocol << ") " << d.vendor << " " << d.model << " serial "
           << d.serial << (d.address.empty() ? "" : " at " + d.address) << "\n";
  }
  if (cameras.empty()) io.out << "  none\n";
}

}  // namespace irdist
