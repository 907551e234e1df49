// EmulatorOptions::IsValid (sim/station_model.h): the station emulator's options checked.
#include <string>

#include "sim/station_model.h"

namespace irdist::sim {
namespace {

bool AxisValid(const AxisOptions& a, const char* name, std::string* why) {
  auto fail = [&](const std::string& m) {
    if (why) *why = std::string("virtual.station.") + name + ": " + m;
    return false;
  };
  if (!(a.min < a.max)) return fail("min must be < max");
  if (a.home < a.min || a.home > a.max) return fail("home must lie within [min, max]");
  if (a.power_on < a.min || a.power_on > a.max) return fail("power_on must lie within [min, max]");
  if (!(a.speed > 0)) return fail("speed must be > 0");
  if (!(a.accel > 0)) return fail("accel must be > 0");
  if (!(a.max_speed == 0.0 || a.max_speed >= a.speed)) {
    return fail("max_speed must be 0 (= speed) or >= speed");
  }
  if (!(a.settle_s >= 0)) return fail("settle_s must be >= 0");
  return true;
}

}  // namespace

bool EmulatorOptions::IsValid(std::string* why) const {
  if (!AxisValid(slide, "slide", why) || !AxisValid(pan, "pan", why) ||
      !AxisValid(tilt, "tilt", why)) {
    return false;
  }
  auto fail = [&](const std::string& m) {
    if (why) *why = "virtual.station: " + m;
    return false;
  };
  auto rate_ok = [](double r) { return r >= 0.0 && r <= 1.0; };
  if (!(homing_speed_factor > 0 && homing_speed_factor <= 1)) {
    return fail("homing_speed_factor must be in (0, 1]");
  }
  if (!(max_current_ma > 0)) return fail("max_current_ma must be > 0");
  if (!(current_noise_ma >= 0)) return fail("current_noise_ma must be >= 0");
  if (!(min_trigger_width_us > 0)) return fail("min_trigger_width_us must be > 0");
  if (!(min_trigger_period_us > min_trigger_width_us)) {
    return fail("min_trigger_period_us must be > min_trigger_width_us");
  }
  if (max_trigger_count < 1) return fail("max_trigger_count must be >= 1");
  if (!(reply_latency_s >= 0)) return fail("reply_latency_s must be >= 0");
  if (!rate_ok(garble_rate) || !rate_ok(drop_rate) || !rate_ok(delay_rate) ||
      !rate_ok(missed_pulse_rate)) {
    return fail("garble_rate, drop_rate, delay_rate and missed_pulse_rate must be in [0, 1]");
  }
  if (!(delay_s >= 0)) return fail("delay_s must be >= 0");
  if (fault_at_move < 0) return fail("fault_at_move must be >= 0 (0 = off)");
  if (!fault.empty() && fault != "refuse" && fault != "estop" && fault != "silent") {
    return fail("fault must be empty, refuse, estop or silent");
  }
  if (!stuck_axis.empty() && stuck_axis != "slide" && stuck_axis != "pan" &&
      stuck_axis != "tilt") {
    return fail("stuck_axis must be empty, slide, pan or tilt");
  }
  return true;
}

}  // namespace irdist::sim
