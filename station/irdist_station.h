#pragma once
// The irdist station (docs/station-protocol.md, docs/devices/irdist_station.md) as one device
// driver filling every role: the three axes, the IRED's current source and the trigger output
// wired to a camera line. It runs over StationClient (framing, retries, reboot recovery).
// Registered as "irdist_station"; a single-box rig file's `station: {port, baud, ...}` means one
// such device filling every role.

#include <cstdint>
#include <memory>

#include "station/driver.h"
#include "station/station_client.h"

namespace irdist {

class IrdistStationDriver : public DeviceDriver,
                            public Motion,
                            public CurrentSource,
                            public Trigger {
 public:
  // Settings (rig file, `station.devices.<name>:`): trigger_width_us (100), trigger_period_us
  // (1000), move_timeout_ms (300000). Axes: all three or none (the station drives all three).
  IrdistStationDriver(const DeviceSpec& spec, std::unique_ptr<Transport> transport);

  Motion* motion() override { return this; }
  CurrentSource* source() override { return this; }
  Trigger* trigger() override { return this; }

  // All three roles share one identity: *IDN? once per call.
  DeviceIdentity Identify() override;

  // Motion
  std::vector<Axis> Axes() const override;
  MotionState State() override;
  void Home() override;
  void StartMove(const StationPosition& target) override;
  void WaitSettled(std::chrono::milliseconds timeout) override;
  void ReadPosition(StationPosition* position) override;
  void Stop() noexcept override;
  AxisSpeed Speed(Axis axis) const override;
  void SetSpeed(Axis axis, double unit_per_s) override;

  // CurrentSource
  void SetCurrent(double bias_ma) override;
  double setpoint_ma() const override { return client_.current_setpoint_ma(); }
  SourceReading Measure() override;
  void Off() noexcept override;

  // Both Motion and CurrentSource: STAT? (reboot -> StationRebooted, ESTOP -> DeviceError).
  void CheckAlive() override;

  // Trigger
  const char* CameraSource() const override { return "Line1"; }
  void Fire(int frame_in_bracket) override;
  std::uint64_t Fired() const override { return fired_; }

  StationClient& client() { return client_; }

 private:
  template <typename F>
  auto Guarded(F&& f) -> decltype(f());
  DeviceSpec spec_;
  std::unique_ptr<Transport> transport_;
  StationClient client_;
  DeviceIdentity identity_;
  double trigger_width_us_ = 100.0;
  double trigger_period_us_ = 1000.0;
  std::uint64_t fired_ = 0;
  double set_speed_[3] = {0.0, 0.0, 0.0};  // SPEED sent since Identify (0: the station's own)
};

// The registry entry (also used by tests that build the driver directly).
DriverInfo IrdistStationInfo();

}  // namespace irdist
