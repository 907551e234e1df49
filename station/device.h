#pragma once
// What every station device driver shares: its identity (checked at connection, before anything
// moves) and its typed errors. A driver is one file in station/ (docs/devices/ has a page per kind);
// its emulator is one file in sim/, written from the same vendor documentation, sharing no code.

#include <string>

#include "base/check.h"

namespace irdist {

// Who answered on a port. `kind` is the driver's name in rig files ("zaber_ascii", "flir_ptu",
// "scpi_source", "irdist_station", "camera_software").
struct DeviceIdentity {
  std::string kind;
  std::string port;  // serial device, or "camera" for the camera's own trigger
  std::string vendor, model, serial, firmware;
  std::string Brief() const {  // "zaber_ascii on /dev/ttyUSB0: Zaber X-LSM200A serial 1234 fw 7.25"
    return kind + " on " + port + ": " + vendor + " " + model + " serial " + serial + " fw " +
           firmware;
  }
};

// A device refused a command, reported a fault, or answered as another device. what() names the
// port, the device's identity, the device's own code or text, and what to do.
class DeviceError : public Error {
 public:
  DeviceError(const DeviceIdentity& device, std::string device_code, const std::string& message,
              const std::string& fix)
      : Error(device.kind + " on " + device.port + " (" + device.vendor + " " + device.model +
              "): " + message + (device_code.empty() ? "" : " [" + device_code + "]") + "; " + fix),
        device_code_(std::move(device_code)) {}
  // The device's own error code or reply text ("-222", "BADDATA", "!P", "-221,\"Settings
  // conflict\"", ...), empty when the error is irdist's.
  const std::string& device_code() const { return device_code_; }

 private:
  std::string device_code_;
};

// A device lost its state behind our back (a power cycle: new boot id, lost home reference, reset
// settings). The caller retakes whatever it captured since the device was last seen consistent.
// recovered(): the driver already re-homed / restored its set-point.
class DeviceRestarted : public Error {
 public:
  DeviceRestarted(const std::string& message, bool recovered)
      : Error(message), recovered_(recovered) {}
  bool recovered() const { return recovered_; }

 private:
  bool recovered_;
};

}  // namespace irdist
