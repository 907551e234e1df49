#include "sim/device_emulator.h"

#include <cmath>
#include <map>

namespace irdist::sim {
namespace {

std::map<std::string, EmulatorInfo>& Registry() {
  static std::map<std::string, EmulatorInfo> emulators;
  return emulators;
}

bool Probability(double p) { return std::isfinite(p) && p >= 0.0 && p <= 1.0; }

}  // namespace

bool EmulatorFaults::IsValid(std::string* why) const {
  const auto fail = [why](const char* text) {
    if (why) *why = text;
    return false;
  };
  if (!Probability(garble_rate)) return fail("garble_rate must be in [0, 1]");
  if (!Probability(drop_rate)) return fail("drop_rate must be in [0, 1]");
  if (!Probability(delay_rate)) return fail("delay_rate must be in [0, 1]");
  if (!std::isfinite(delay_s) || delay_s < 0.0) return fail("delay_s must be >= 0");
  if (!std::isfinite(power_cycle_after_s)) return fail("power_cycle_after_s must be finite");
  if (!stuck_axis.empty() && stuck_axis != "slide" && stuck_axis != "pan" && stuck_axis != "tilt")
    return fail("stuck_axis must be slide, pan, tilt or empty");
  return true;
}

EmulatorRegistration::EmulatorRegistration(EmulatorInfo info) {
  const std::string driver = info.driver;
  Registry()[driver] = std::move(info);
}

const EmulatorInfo* FindEmulator(const std::string& driver) {
  const auto it = Registry().find(driver);
  return it == Registry().end() ? nullptr : &it->second;
}

}  // namespace irdist::sim
