// Cameras found by Aravis (discovery) and a camera named by id, serial or address.
#include "acquisition/aravis_internal.h"

namespace irdist {

bool LooksLikeIpv4(const std::string& name) {
  int dots = 0;
  for (char c : name) {
    if (c == '.') {
      ++dots;
    } else if (c < '0' || c > '9') {
      return false;
    }
  }
  return dots == 3;
}

std::vector<DeviceInfo> ListCameras() {
  arv_update_device_list();
  std::vector<DeviceInfo> devices;
  const unsigned int count = arv_get_n_devices();
  for (unsigned int i = 0; i < count; ++i) {
    DeviceInfo info;
    info.id = OrEmpty(arv_get_device_id(i));
    info.vendor = OrEmpty(arv_get_device_vendor(i));
    info.model = OrEmpty(arv_get_device_model(i));
    info.serial = OrEmpty(arv_get_device_serial_nbr(i));
    info.address = OrEmpty(arv_get_device_address(i));
    info.protocol = OrEmpty(arv_get_device_protocol(i));
    devices.push_back(std::move(info));
  }
  return devices;
}

DeviceInfo ResolveCamera(const std::string& id_serial_or_ip,
                         const std::vector<DeviceInfo>& devices) {
  for (const auto& device : devices) {
    if (device.id == id_serial_or_ip || device.serial == id_serial_or_ip) return device;
  }
  std::vector<std::string> names;
  for (const auto& device : devices) names.push_back(device.id + " (" + device.address + ")");
  throw CameraError("no camera named '" + id_serial_or_ip + "' (id, serial or IP) answers; " +
                    "cameras found: [" + JoinNames(names) +
                    "]. Check power and cabling, or give the camera's IP address in the rig "
                    "file (camera: id:).");
}

}  // namespace irdist
