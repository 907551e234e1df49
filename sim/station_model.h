#pragma once
// The station model: the virtual rig's motion station (slide + pan + tilt), IRED current source,
// trigger output and SCPI-like error queue, as a pure state machine in simulated time. It knows
// the command table of docs/station-protocol.md (section 5) but nothing of lines, frames,
// checksums, retransmissions or ptys: sim/station_emulator.cc is the thin layer that reads framed
// lines from a pty and calls Execute(). A test drives the model directly: Execute("MOVE ...", t),
// Advance(t + 1), Execute("POS?", t + 1), with no thread and no wall clock.
//
// What the station does to the physical world goes through StationEffects (the emulator binds it
// to the shared World: pose, IRED current, trigger pulses).

#include <cstdint>
#include <memory>
#include <optional>
#include <random>
#include <string>

#include "sim/motion_profile.h"
#include "sim/station_model_text.h"  // ParseProtocolInt
#include "sim/trajectory.h"

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
  // The fastest cruise speed `SPEED` accepts (unit/s); 0: `speed` (the power-on speed) is also
  // the fastest.
  double max_speed = 0.0;
  double MaxSpeed() const { return max_speed > 0.0 ? max_speed : speed; }
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

// What the station changes in the world around it.
class StationEffects {
 public:
  virtual ~StationEffects() = default;
  virtual void SetPose(double slide_mm, double pan_deg, double tilt_deg, bool moving) = 0;
  virtual void SetCurrent(double bias_ma) = 0;
  virtual void FireTrigger() = 0;
  // An axis starts following `profile` (a move, a stop, a halt, a power-up at rest): the exact
  // trajectory the world keeps (sim/trajectory.h). Called before the SetPose that follows.
  virtual void SetAxisMotion(RigAxis /*axis*/, const MotionProfile& /*profile*/) {}
  // After every power-up (first start and reboots): the link layer forgets its framing state.
  virtual void PoweredUp() {}
};

class StationModel {
 public:
  // Throws irdist::Error when `options` are not valid (EmulatorOptions::IsValid). Starts in the
  // BOOTING state; call PowerOn() (or Reboot()) before the first command.
  StationModel(StationEffects& effects, EmulatorOptions options);
  ~StationModel();
  StationModel(const StationModel&) = delete;
  StationModel& operator=(const StationModel&) = delete;

  // Powered up before anyone listened: unhomed, IRED off, ready at once (no boot delay).
  void PowerOn(double now_s);
  // Executes one unframed command ("MOVE 150000,0,0") at simulated time now_s and returns the
  // reply body ("OK ..." or "ERR <code>,\"<message>\""); a failed command also queues its error.
  // Not to be called while Booting(): a booting station hears nothing (the link layer discards).
  std::string Execute(const std::string& command, double now_s);
  // Advances motion, settling, homing, booting, scheduled reboots, the link watchdog and the
  // trigger train to now_s (at most one trigger pulse per call).
  void Advance(double now_s);
  // A valid framed request arrived (feeds the SYST:WDOG link watchdog).
  void NoteValidRequest(double now_s);
  // Queues an error the link layer detected (-102 syntax, 203 checksum, 205 line too long).
  void PushError(int code);

  // --- faults and buttons ---
  void Reboot(double now_s);              // power-cycles now: new boot id, unhomed, IRED off
  void PressEmergencyStop(double now_s);  // as ESTOP: halt, IRED off, state ESTOP
  void RebootDuringNextMove(double after_s);
  EmulatorOptions& options();             // fault rates may be changed between calls

  // --- observation ---
  bool Booting() const;           // deaf: received bytes are discarded
  bool Silent() const;            // fault "silent" struck: no reply is ever sent again
  std::optional<double> NextPulseS() const;  // simulated time of the next trigger pulse
  std::string StateName() const;  // as STAT? reports it: UNHOMED, HOMING, IDLE, ...
  std::string BootId() const;
  std::uint64_t Reboots() const;
  // The station's one random generator (noise and faults), shared with the link layer's faults so
  // that one seed reproduces a whole run. Chance(p): true with probability p.
  std::mt19937_64& Random();
  bool Chance(double p);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace irdist::sim
