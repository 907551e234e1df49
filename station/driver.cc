#include "station/driver.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "base/input_error.h"

namespace irdist {
namespace {

std::map<std::string, DriverInfo>& Registry() {
  static std::map<std::string, DriverInfo> drivers;
  return drivers;
}

std::string Join(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

}  // namespace

DriverRegistration::DriverRegistration(DriverInfo info) {
  const std::string name = info.name;
  Registry()[name] = std::move(info);
}

const DriverInfo* FindDriver(const std::string& name) {
  const auto it = Registry().find(name);
  return it == Registry().end() ? nullptr : &it->second;
}

std::vector<std::string> DriverNames() {
  std::vector<std::string> names;
  for (const auto& [name, info] : Registry()) names.push_back(name);
  return names;
}

double DeviceSpec::Number(const std::string& key, double fallback) const {
  const auto it = settings.find(key);
  if (it == settings.end()) return fallback;
  const std::string& text = it->second.text;
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(value)) {
    throw InputError(file, it->second.line, 0,
                     "station.devices." + name + "." + key + " must be a finite number, not '" +
                         text + "'");
  }
  return value;
}

std::string DeviceSpec::Text(const std::string& key, const std::string& fallback) const {
  const auto it = settings.find(key);
  return it == settings.end() ? fallback : it->second.text;
}

void DeviceSpec::CheckKnown(const std::vector<std::string>& keys) const {
  for (const auto& [key, setting] : settings) {
    if (std::find(keys.begin(), keys.end(), key) == keys.end()) {
      throw InputError(file, setting.line, 0,
                       "unknown key '" + key + "' in station.devices." + name + " (driver " +
                           driver + "); valid keys: driver, port, baud, reply_timeout_ms, axes" +
                           (keys.empty() ? std::string() : ", " + Join(keys)));
    }
  }
}

}  // namespace irdist
