#pragma once
// The source role: the IRED's current source (the irdist station's own, or an IEEE 488.2 / SCPI
// SourceMeter such as a Keithley 2400). The IRED must be off whenever a run stops, for any reason:
// Off() is called on every exit path and never throws.

#include "station/device.h"

namespace irdist {

struct SourceReading {
  double current_ma = 0.0;     // measured current
  double voltage_v = 0.0;      // measured voltage (0 when the device cannot measure it)
  bool in_compliance = false;  // the voltage limit is reached: the current is not what was set
  bool output_on = false;
};

class CurrentSource {
 public:
  virtual ~CurrentSource() = default;
  // Asks the device who it is and checks it (DeviceError on a wrong device); puts it in a known
  // state with the output off (source function current, voltage compliance from the rig file).
  virtual DeviceIdentity Identify() = 0;
  // Sets the IRED current; 0 switches the output off. Throws DeviceError (the device's error
  // queue is read after each set), LinkError.
  virtual void SetCurrent(double bias_ma) = 0;
  virtual double setpoint_ma() const = 0;
  // One measurement. Throws DeviceError, LinkError.
  virtual SourceReading Measure() = 0;
  // For `irdist station` by hand (before Identify()): Identify() takes an output found on as it
  // is (its set-point read back, nothing reset), and the driver leaves the output as it is when
  // it is destroyed. Without it, Identify() resets the device and destruction switches it off.
  virtual void KeepOutput() {}
  // Output off, best effort, on every exit path (Ctrl-C, errors, end of run). Never throws.
  virtual void Off() noexcept = 0;
  // Throws DeviceRestarted when the device lost its state (power cycle), DeviceError when its
  // output tripped. Cheap: one exchange.
  virtual void CheckAlive() = 0;
};

}  // namespace irdist
