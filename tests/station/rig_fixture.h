#pragma once
// A virtual station for the station tests: a World running fast, the emulator on a real pty, a
// SerialTransport logging to a file in the build tree, and a StationClient.

#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "sim/device_emulator.h"
#include "sim/station_emulator.h"
#include "sim/world.h"
#include "station/line_log.h"
#include "station/serial_transport.h"
#include "station/station.h"
#include "station/station_client.h"

namespace irdist::testing {

struct VirtualStation {
  explicit VirtualStation(double time_scale, sim::EmulatorOptions emulator_options = {},
                          ClientOptions client_options = FastClient())
      : world(time_scale), emulator(world, emulator_options) {
    port = emulator.Start();
    const std::string name = ::testing::UnitTest::GetInstance()->current_test_info()->name();
    log = std::make_unique<LineLog>(std::string(IRDIST_BINARY_DIR) + "/station_test_" + name +
                                    ".log");
    transport = std::make_unique<SerialTransport>(port, SerialOptions{}, log.get());
    client = std::make_unique<StationClient>(*transport, client_options);
  }
  static ClientOptions FastClient() {
    ClientOptions o;
    o.reply_timeout = std::chrono::milliseconds(150);
    o.poll_period = std::chrono::milliseconds(2);
    o.move_timeout = std::chrono::milliseconds(20000);
    o.max_retries = 10;
    return o;
  }
  sim::World world;
  sim::StationEmulator emulator;
  std::string port;
  std::unique_ptr<LineLog> log;
  std::unique_ptr<SerialTransport> transport;
  std::unique_ptr<StationClient> client;
};

// The emulator behind a composed Station of one irdist_station device filling every role (what a
// single-box rig file means), logging to a file in the build tree.
struct VirtualStationRig {
  explicit VirtualStationRig(double time_scale, sim::EmulatorOptions emulator_options = {},
                             double current_tolerance_ma = 5.0)
      : world(time_scale), emulator(world, emulator_options) {
    port = emulator.Start();
    const std::string name = ::testing::UnitTest::GetInstance()->current_test_info()->name();
    log = std::make_unique<LineLog>(std::string(IRDIST_BINARY_DIR) + "/station_test_" + name +
                                    ".log");
    StationOptions options;
    options.log = log.get();
    station = std::make_unique<Station>(Spec(port, current_tolerance_ma), options);
  }
  static StationSpec Spec(const std::string& port, double current_tolerance_ma) {
    DeviceSpec device;
    device.name = "station";
    device.driver = "irdist_station";
    device.port = port;
    device.reply_timeout_ms = 150;
    device.settings["move_timeout_ms"] = {"20000", 1};
    StationSpec spec;
    spec.devices = {device};
    spec.motion = {"station"};
    spec.source = "station";
    spec.trigger = "station";
    spec.current_tolerance_ma = current_tolerance_ma;
    return spec;
  }
  sim::World world;
  sim::StationEmulator emulator;
  std::string port;
  std::unique_ptr<LineLog> log;
  std::unique_ptr<Station> station;
};

// Duration of a trapezoidal move from rest to rest (simulated seconds).
inline double TrapezoidS(double distance, double speed, double accel) {
  if (distance <= 0) return 0.0;
  if (distance >= speed * speed / accel) return distance / speed + speed / accel;
  return 2.0 * std::sqrt(distance / accel);
}

// A link as hostile as a bad lab's: 10% of the replies dropped, 10% delayed by `delay_s`
// (simulated seconds), for a driver's test against its emulator.
inline sim::EmulatorFaults LossyReplies(double delay_s) {
  sim::EmulatorFaults faults;
  faults.drop_rate = 0.1;
  faults.delay_rate = 0.1;
  faults.delay_s = delay_s;
  return faults;
}

// The driver's motion role, identified and homed.
inline Motion& IdentifiedAndHomed(DeviceDriver& driver) {
  Motion& motion = *driver.motion();
  motion.Identify();
  motion.Home();
  return motion;
}

}  // namespace irdist::testing
