#pragma once
// A device driver as the station composition sees it: one file per device kind in station/
// registers itself here with IRDIST_REGISTER_DRIVER (irdist_station, zaber_ascii, flir_ptu,
// scpi_source). The rig file's `station.devices.<name>:` entry becomes a DeviceSpec; the
// composition (station/station.h) opens the port, builds the driver and asks it for the roles it
// fills. Adding a device kind: one driver file here, one emulator in sim/, a page in docs/devices/.

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "station/device.h"
#include "station/motion.h"
#include "station/source.h"
#include "station/transport.h"
#include "station/trigger.h"

namespace irdist {

// One driver-specific key of a device's rig-file entry, as written, with where it was written.
struct DeviceSetting {
  std::string text;
  int line = 0;  // 1-based line in the rig file
};

// One entry of the rig file's `station.devices:` map.
struct DeviceSpec {
  std::string name;    // the entry's key: "slide", "head", "source", "station"
  std::string driver;  // registered driver name
  std::string port = "auto";  // serial device; "auto" = the virtual rig's emulator of this device
  int baud = 0;               // 0 = the driver's default
  int reply_timeout_ms = 0;   // 0 = the driver's default
  // Motion devices: which rig axes the device drives and its own address of each ("1" = Zaber
  // device 1, "1 2" = device 1 axis 2, "pan"/"tilt" on a PTU).
  std::map<Axis, std::string> axes;
  std::map<std::string, DeviceSetting> settings;  // every other key of the entry
  std::string file;  // the rig file, for errors
  int line = 0;      // line of the entry
  // Strict reading of `settings` for the driver: unknown keys and bad values are InputErrors
  // naming file:line and the valid keys. A missing key gives `fallback`.
  double Number(const std::string& key, double fallback) const;
  std::string Text(const std::string& key, const std::string& fallback) const;
  void CheckKnown(const std::vector<std::string>& keys) const;  // every key is one of these
};

// A connected device and the roles it can fill (nullptr: not this one). The driver owns its
// Transport.
class DeviceDriver {
 public:
  virtual ~DeviceDriver() = default;
  virtual Motion* motion() { return nullptr; }
  virtual CurrentSource* source() { return nullptr; }
  virtual Trigger* trigger() { return nullptr; }
};

struct DriverInfo {
  std::string name;         // rig-file name
  std::string line_end;     // written after each command: "\n", "\r\n", " "
  bool cr_ends_reply = false;  // a '\r' alone ends a reply line (the FLIR PTU), besides '\n'
  unsigned int default_baud = 9600;
  int default_reply_timeout_ms = 500;
  std::vector<std::string> roles;  // "motion", "source", "trigger": what it can fill
  std::string doc;                 // docs/devices/<name>.md
  // Checks the spec at rig-load time (settings, axes): throws InputError. Nothing is opened.
  std::function<void(const DeviceSpec&)> validate;
  // Builds the driver over an open transport. Nothing is sent before the composition calls
  // Identify() on the roles.
  std::function<std::unique_ptr<DeviceDriver>(const DeviceSpec&, std::unique_ptr<Transport>)>
      create;
};

// Registered drivers by name; nullptr when unknown.
const DriverInfo* FindDriver(const std::string& name);
std::vector<std::string> DriverNames();

struct DriverRegistration {
  explicit DriverRegistration(DriverInfo info);
};

}  // namespace irdist

// At namespace scope in the driver's .cc file:
//   IRDIST_REGISTER_DRIVER(zaber_ascii, MakeZaberInfo());
#define IRDIST_REGISTER_DRIVER(name, info) \
  static const ::irdist::DriverRegistration irdist_driver_registration_##name(info)
