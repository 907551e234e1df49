#pragma once
// The station emulator: the virtual rig's motion station (slide + pan + tilt), IRED current source
// and trigger output, speaking the wire protocol of docs/station-protocol.md on a pseudo-terminal.
// It drives the shared World (SetPose / SetCurrent / FireTrigger) in simulated time, so the virtual
// camera sees exactly what the protocol commanded. Faults (garbled bytes, dropped or delayed
// replies, reboots, a stuck axis, missed trigger pulses) are injected from the rig file's
// `virtual.station:` subsection or at run time through the setters below.

#include <cstdint>
#include <memory>
#include <string>

#include "base/check.h"
#include "sim/world.h"

namespace irdist::sim {

// One axis's motion parameters (trapezoidal profile), in the axis's own unit (mm or deg).
struct AxisOptions {
  double min = 0.0;           // soft limit, low end (unit of the axis)
  double max = 0.0;           // soft limit, high end
  double home = 0.0;          // position reached by homing
  double speed = 1.0;         // cruise speed, unit/s (simulated time)
  double accel = 1.0;         // acceleration and deceleration, unit/s^2
  double settle_s = 0.05;     // settle time after the profile ends before the axis reports settled
  double power_on = 0.0;      // (uncalibrated) position the axis rests at after power-up
};

struct EmulatorOptions {
  // Axes: slide in mm, pan and tilt in degrees. Limits match recipes/rigs/virtual.yaml station:.
  AxisOptions slide{1000.0, 3500.0, 1000.0, 200.0, 400.0, 0.10, 2000.0};
  AxisOptions pan{-45.0, 45.0, 0.0, 30.0, 60.0, 0.05, 0.0};
  AxisOptions tilt{-45.0, 45.0, 0.0, 30.0, 60.0, 0.05, 0.0};
  double homing_speed_factor = 1.0;  // homing moves at this fraction of cruise speed (0, 1]
  double max_current_ma = 600.0;     // IRED current source range [0, max]
  double current_noise_ma = 0.05;    // standard deviation of the measured current's noise
  double min_trigger_width_us = 1.0;     // shortest accepted pulse width
  double min_trigger_period_us = 1000.0; // shortest accepted pulse period
  std::uint32_t max_trigger_count = 100000;  // most pulses in one TRIG:COUNT
  double reply_latency_s = 0.0005;   // simulated processing time before each reply
  std::uint64_t seed = 1;            // seed of the noise and fault random generators
  // --- fault injection (all off by default) ---
  double garble_rate = 0.0;          // probability that each byte of a reply is corrupted
  double drop_rate = 0.0;            // probability that a reply is not sent at all
  double delay_rate = 0.0;           // probability that a reply is delayed by delay_s
  double delay_s = 0.5;              // simulated delay of a delayed reply
  double reboot_after_s = -1.0;      // reboot once, this many simulated s into the first move (<0 off)
  std::string stuck_axis;            // "", "slide", "pan" or "tilt": this axis never moves
  double missed_pulse_rate = 0.0;    // probability that a trigger pulse is not emitted
  // At the fault_at_move-th MOVE to a new target (1-based, 0 = off): `refuse` answers -222 (a
  // refused move), `estop` accepts it and the emergency stop is pressed at once, `silent`
  // accepts it and the station never answers again.
  int fault_at_move = 0;
  std::string fault;
  bool open_circuit = false;         // the IRED's circuit is open: no current flows, MEAS:CURR? ~0
  // A deliberately non-conforming station (for the conformance suite's own test): refuses
  // `SOUR:CURR 0` in ESTOP (202), as protocol v1 drafts did.
  bool refuse_current_off_in_estop = false;

  bool IsValid(std::string* why) const;
};

// Reads the `virtual.station:` subsection of a rig file (keys as the field names above, axes as
// maps with min/max/home/speed/accel/settle_s/power_on); station.limits are used for the soft
// limits when present. Missing file sections give the defaults; an unknown (misspelt) key is an
// InputError naming file:line (base/yaml_fields.h); a malformed value throws irdist::Error naming
// the file and key.
EmulatorOptions LoadEmulatorOptions(const std::string& rig_path);

class StationEmulator {
 public:
  StationEmulator(World& world, EmulatorOptions options);
  ~StationEmulator();  // stops
  StationEmulator(const StationEmulator&) = delete;
  StationEmulator& operator=(const StationEmulator&) = delete;

  // Opens a pty (openpty, raw mode), starts the emulator's thread, returns the slave path
  // (e.g. /dev/pts/7) for the client to open. Throws irdist::Error if the pty cannot be opened.
  std::string Start();
  // Stops the thread and closes the pty. Idempotent.
  void Stop();

  // --- control interface (thread-safe, take effect at once) ---
  void SetGarbleRate(double rate);
  void SetDropRate(double rate);
  void SetDelay(double rate, double delay_s);
  void SetStuckAxis(const std::string& axis);  // "" clears
  void SetMissedPulseRate(double rate);
  // Reboots after `after_s` simulated seconds of the next move (0 = at the next move's start).
  void RebootDuringNextMove(double after_s);
  // The station's emergency-stop button: as the ESTOP command (halt, IRED off, state ESTOP).
  void PressEmergencyStop();
  // Power-cycles now: new boot id, unhomed, IRED off, motion and trigger stopped, errors cleared.
  void Reboot();

  // --- observation (for tests) ---
  std::string BootId() const;
  std::uint64_t Reboots() const;         // number of reboots since Start
  std::uint64_t LinesReceived() const;   // command lines received (including bad ones)
  std::uint64_t RepliesDropped() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace irdist::sim
