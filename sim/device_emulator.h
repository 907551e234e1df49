#pragma once
// A station device's emulator on the virtual rig: one file per device kind in sim/ (zaber_ascii,
// flir_ptu, scpi_source; the irdist station is StationEmulator), written from the vendor's
// documentation and sharing no code with station/'s drivers. Each serves its device's wire
// protocol on its own pseudo-terminal and writes into the one World (axes, IRED current, trigger).
// VirtualRig starts one for every `station.devices:` entry of the rig file whose port is `auto`,
// with the fault knobs of `virtual.devices.<name>:`.

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "sim/world.h"

namespace irdist::sim {

// The faults every emulator offers (all off by default), as in `virtual.devices.<name>:`.
struct EmulatorFaults {
  double garble_rate = 0.0;     // probability that each byte of a reply is corrupted
  double drop_rate = 0.0;       // probability that a reply is not sent
  double delay_rate = 0.0;      // probability that a reply is delayed by delay_s
  double delay_s = 0.5;         // simulated seconds
  double power_cycle_after_s = -1.0;  // power-cycle once, this long into the first move (< 0 off)
  std::string stuck_axis;       // a rig axis ("slide", "pan", "tilt") that never moves
  bool IsValid(std::string* why) const;
};

class DeviceEmulator {
 public:
  virtual ~DeviceEmulator() = default;
  // Opens its pty (raw mode), starts its thread; returns the slave path for the driver to open.
  virtual std::string Start() = 0;
  virtual void Stop() = 0;  // idempotent
  // Power-cycles now (lost home, output off, settings reset).
  virtual void PowerCycle() = 0;
  virtual void SetFaults(const EmulatorFaults& faults) = 0;
};

// What VirtualRig hands a device emulator: which entry of the rig file is its own. The emulator
// reads `station.devices.<name>` (axes, addresses) and `virtual.devices.<name>` (its physics and
// faults) from `rig_text` with base/yaml_fields.h, so errors carry the file's lines.
struct EmulatorSpec {
  std::string name;      // station.devices key
  std::string driver;    // station.devices.<name>.driver
  std::string rig_path;  // for errors (file:line)
  std::string rig_text;  // the whole rig file
  std::uint64_t seed = 1;
};

struct EmulatorInfo {
  std::string driver;  // the station/ driver name it emulates
  // Builds the emulator (parses its spec strictly with base/yaml_fields.h: unknown keys are
  // InputErrors with file:line). Does not start it.
  std::function<std::unique_ptr<DeviceEmulator>(World&, const EmulatorSpec&)> create;
};

const EmulatorInfo* FindEmulator(const std::string& driver);

// A client that made the emulator's pty exclusive (TIOCEXCL, as irdist's serial transport does)
// and died without clearing it (kill -9) leaves the flag on the tty, which lives on because the
// emulator holds its slave side open: every later open() but root's fails with EBUSY. Clears the
// flag when it is set and no process holds an flock on the pty (irdist's transport takes the
// flock before TIOCEXCL and clears the flag before it lets the flock go). Returns whether it
// cleared it. The emulators call it through AbandonedExclusiveWatch while they serve.
bool ReleaseAbandonedExclusive(int slave_fd);

// ReleaseAbandonedExclusive at most every 0.25 host seconds, from a serving loop.
class AbandonedExclusiveWatch {
 public:
  void Poll(int slave_fd);

 private:
  std::chrono::steady_clock::time_point next_{};
};

struct EmulatorRegistration {
  explicit EmulatorRegistration(EmulatorInfo info);
};

}  // namespace irdist::sim

#define IRDIST_REGISTER_EMULATOR(name, info) \
  static const ::irdist::sim::EmulatorRegistration irdist_emulator_registration_##name(info)
