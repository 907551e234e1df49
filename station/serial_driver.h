#pragma once
// Station-internal (included by the drivers' .cc files only, never by a public header): what the
// line-protocol drivers (zaber_ascii, flir_ptu, scpi_source) share at registration: their
// DriverInfo and the InputError of a bad rig-file entry.

#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "base/input_error.h"
#include "station/driver.h"

namespace irdist {

// The InputError of a bad `station.devices.<name>:` entry of `driver`, at the entry's line:
// "station.devices.<name> (<driver>): <message>; see docs/devices/<driver>.md".
[[noreturn]] inline void InvalidEntry(const DeviceSpec& spec, const std::string& driver,
                                      const std::string& message) {
  throw InputError(spec.file, spec.line, 0, "station.devices." + spec.name + " (" + driver +
                                                "): " + message + "; see docs/devices/" +
                                                driver + ".md");
}

// The registration of the line-protocol driver `Driver` (constructed from the spec and the open
// transport) named `name`, documented in docs/devices/<name>.md: `validate` checks an entry at
// rig-load time and again before the driver is built.
template <typename Driver>
DriverInfo SerialDriverInfo(const std::string& name, const std::string& line_end,
                            unsigned int default_baud, int default_reply_timeout_ms,
                            std::vector<std::string> roles,
                            std::function<void(const DeviceSpec&)> validate) {
  DriverInfo info;
  info.name = name;
  info.line_end = line_end;
  info.default_baud = default_baud;
  info.default_reply_timeout_ms = default_reply_timeout_ms;
  info.roles = std::move(roles);
  info.doc = "docs/devices/" + name + ".md";
  info.validate = validate;
  info.create = [validate](const DeviceSpec& spec, std::unique_ptr<Transport> link) {
    validate(spec);
    return std::unique_ptr<DeviceDriver>(new Driver(spec, std::move(link)));
  };
  return info;
}

}  // namespace irdist
