#pragma once
// The station emulator: the station model (sim/station_model.h) behind the wire protocol of
// docs/station-protocol.md on a pseudo-terminal. This layer owns the pty thread, line framing,
// checksums, retransmission and the link faults (garbled, dropped, delayed replies); every command
// is executed by the model, which drives the shared World in simulated time, so the virtual
// camera sees exactly what the protocol commanded. Faults (garbled bytes, dropped or delayed
// replies, reboots, a stuck axis, missed trigger pulses) are injected from the rig file's
// `virtual.station:` subsection or at run time through the setters below.

#include <cstdint>
#include <memory>
#include <string>

#include "base/check.h"
#include "sim/station_model.h"
#include "sim/world.h"

namespace irdist::sim {

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
