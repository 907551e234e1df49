#pragma once
// The SCPI current source's own faults (sim/scpi_emulator.cc, driver `scpi_source`), settable at
// run time in addition to the EmulatorFaults every emulator has. The same keys are read from
// `virtual.devices.<name>:` (docs/virtual-rig.md).

#include "sim/device_emulator.h"

namespace irdist::sim {

struct SourceFaults {
  bool open_circuit = false;        // the IRED is disconnected: 0 A flows, V sits at compliance
  double extra_resistance_ohm = 0;  // added to the load's series resistance (reaches compliance)
  double trip_after_s = -1.0;       // the output trips off this long after each turn-on (< 0 off)
  bool IsValid(std::string* why) const;
};

// Sets the source faults of a `scpi_source` emulator; throws irdist::Error for any other kind.
void SetSourceFaults(DeviceEmulator& emulator, const SourceFaults& faults);

}  // namespace irdist::sim
