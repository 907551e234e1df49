// The station emulator's options checked (sim/station_options.cc, EmulatorOptions::IsValid): the
// defaults pass; each bad field is refused with the rig file's key that names it.
#include <gtest/gtest.h>

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "sim/station_model.h"

namespace irdist::sim {
namespace {

TEST(EmulatorOptions, DefaultsAreValid) {
  std::string why;
  EXPECT_TRUE(EmulatorOptions().IsValid(&why)) << why;
  EXPECT_TRUE(EmulatorOptions().IsValid(nullptr));
}

TEST(EmulatorOptions, RefusesEachBadFieldWithItsKey) {
  using Change = std::function<void(EmulatorOptions&)>;
  const std::vector<std::pair<Change, std::string>> cases = {
      {[](EmulatorOptions& o) { o.slide.max = o.slide.min; },
       "virtual.station.slide: min must be < max"},
      {[](EmulatorOptions& o) { o.pan.home = 90.0; }, "virtual.station.pan: home"},
      {[](EmulatorOptions& o) { o.tilt.power_on = -90.0; }, "virtual.station.tilt: power_on"},
      {[](EmulatorOptions& o) { o.slide.speed = 0.0; }, "virtual.station.slide: speed"},
      {[](EmulatorOptions& o) { o.pan.accel = -1.0; }, "virtual.station.pan: accel"},
      {[](EmulatorOptions& o) { o.tilt.max_speed = 1.0; }, "virtual.station.tilt: max_speed"},
      {[](EmulatorOptions& o) { o.slide.settle_s = -0.1; }, "virtual.station.slide: settle_s"},
      {[](EmulatorOptions& o) { o.homing_speed_factor = 1.5; },
       "virtual.station: homing_speed_factor"},
      {[](EmulatorOptions& o) { o.max_current_ma = 0.0; }, "virtual.station: max_current_ma"},
      {[](EmulatorOptions& o) { o.current_noise_ma = -1.0; }, "virtual.station: current_noise_ma"},
      {[](EmulatorOptions& o) { o.min_trigger_width_us = 0.0; },
       "virtual.station: min_trigger_width_us"},
      {[](EmulatorOptions& o) { o.min_trigger_period_us = 1.0; },
       "virtual.station: min_trigger_period_us"},
      {[](EmulatorOptions& o) { o.max_trigger_count = 0; }, "virtual.station: max_trigger_count"},
      {[](EmulatorOptions& o) { o.reply_latency_s = -1.0; }, "virtual.station: reply_latency_s"},
      {[](EmulatorOptions& o) { o.drop_rate = 1.5; }, "virtual.station: garble_rate, drop_rate"},
      {[](EmulatorOptions& o) { o.delay_s = -1.0; }, "virtual.station: delay_s"},
      {[](EmulatorOptions& o) { o.fault_at_move = -1; }, "virtual.station: fault_at_move"},
      {[](EmulatorOptions& o) { o.fault = "explode"; }, "virtual.station: fault must be"},
      {[](EmulatorOptions& o) { o.stuck_axis = "roll"; }, "virtual.station: stuck_axis"},
  };
  for (const auto& [change, message] : cases) {
    EmulatorOptions options;
    change(options);
    std::string why;
    EXPECT_FALSE(options.IsValid(&why)) << message;
    EXPECT_EQ(why.rfind(message, 0), 0u) << why;
  }
}

}  // namespace
}  // namespace irdist::sim
