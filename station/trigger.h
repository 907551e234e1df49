#pragma once
// The trigger role: what makes the camera take a frame. The irdist station's trigger output wired
// to a camera line, or the camera's own software trigger (app/ builds that one from the camera:
// station/ never sees a camera), or the camera's timer.

#include <cstdint>

#include "station/device.h"

namespace irdist {

class Trigger {
 public:
  virtual ~Trigger() = default;
  virtual DeviceIdentity Identify() = 0;
  // The camera's TriggerSource this trigger drives ("Line1", "Software", ...): checked against the
  // rig file's camera.trigger_source at plan time.
  virtual const char* CameraSource() const = 0;
  // Fires one frame (`frame_in_bracket`, -1 for a warm-up frame) and returns once the pulse is
  // out (or the command accepted). Throws DeviceError, LinkError, CameraError (software trigger).
  virtual void Fire(int frame_in_bracket) = 0;
  // Pulses emitted since Identify() (frames asked for), for the run's report.
  virtual std::uint64_t Fired() const = 0;
};

}  // namespace irdist
