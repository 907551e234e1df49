#pragma once
// The virtual rig's GigE Vision camera: an Aravis fake camera (GVCP/GVSP) on 127.0.0.1, described
// by sim/virtual_camera.xml, whose frames are rendered by the Renderer for the state of the World
// during each exposure and with the exposure that frame was taken with.
//
// It powers up free-running (TriggerMode Off, 25 frames/s). With TriggerMode On and TriggerSource
// Line1, each World::FireTrigger() pulse starts a frame; TriggerSource Software uses the
// TriggerSoftware command. Timing: a frame occupies the camera for exposure + readout (simulated
// time, scaled by the rig's time_scale) before it is sent. Faults: whole frames dropped at
// drop_frame_rate, GVSP packets lost at lost_packet_ratio.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "base/check.h"
#include "sim/rig_physics.h"
#include "sim/world.h"

namespace irdist::sim {

// The camera could not start (port taken, Aravis failure). The message says what to do.
class CameraServerError : public Error {
 public:
  using Error::Error;
};

// What the camera did for one frame it exposed.
struct FrameRecord {
  std::uint64_t index = 0;        // camera-side frame counter since Start (1, 2, ...)
  double sim_time_s = 0.0;        // simulated time at the start of the exposure
  double exposure_us = 0.0;       // exposure the frame was taken with
  double slide_mm = 0.0;          // pose at the start of the exposure
  double theta_deg = 0.0;
  double bias_ma = 0.0;
  double junction_rise_k = 0.0;
  bool moving = false;            // an axis moved during the exposure
  bool dropped = false;           // the frame was never sent (fault injection)
  std::string format;             // Mono8 / Mono12 / Mono16
};

class CameraServer {
 public:
  CameraServer(World& world, const RigPhysics& physics);
  ~CameraServer();  // stops
  CameraServer(const CameraServer&) = delete;
  CameraServer& operator=(const CameraServer&) = delete;

  // Checks that UDP port 3956 on 127.0.0.1 is free, then starts the fake camera and connects
  // the World's trigger line. Throws CameraServerError.
  void Start();
  // Stops the camera and disconnects the trigger line. Idempotent.
  void Stop();
  bool running() const;

  std::string address() const { return "127.0.0.1"; }
  std::string serial() const;
  std::string device_id() const;  // as Aravis names it: "Aravis-Fake-<serial>"

  // Fault injection, effective from the next frame.
  void SetDropFrameRate(double rate);
  void SetLostPacketRatio(double ratio);

  // Observation (thread-safe).
  std::uint64_t FramesExposed() const;
  std::uint64_t FramesDropped() const;
  std::uint64_t LinePulsesAccepted() const;  // Line1 pulses that triggered (mode On, source Line1)
  std::vector<FrameRecord> RecentFrames() const;  // the last up to 1000 frames, oldest first

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace irdist::sim
