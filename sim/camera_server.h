#pragma once
// The virtual rig's GigE Vision camera on 127.0.0.1, described by sim/virtual_camera.xml, whose
// frames are rendered by the Renderer for the state of the World during each exposure and with the
// exposure that frame was taken with.
//
// It is written from the GigE Vision protocol as a device implements it: a control channel (GVCP on
// UDP 3956: discovery, register and memory reads and writes, packet resend) served by its own
// thread at all times, also while a frame is exposed or read out, and a sensor thread that exposes,
// reads out and streams frames (GVSP: leader, payload packets, trailer). Aravis's ArvFakeCamera is
// only its register map (bootstrap registers and the XML file in memory). The parts are defined in
// sim/camera_server_{device,gvcp,gvsp,sensor}.cc over the state of sim/camera_server_impl.h.
//
// It powers up free-running (TriggerMode Off, 25 frames/s). With TriggerMode On, each trigger of
// the selected TriggerSource starts a frame: a World::FireTrigger() pulse for Line1, the
// TriggerSoftware command for Software. A trigger that arrives while a frame is exposed or read out
// is queued (up to 4) and starts the next frame as soon as the sensor is free. The exposure time is
// latched when a frame starts. Timing: a frame occupies the sensor for exposure + readout (simulated
// time, scaled by the rig's time_scale) before it is sent.
//
// With ChunkModeActive and ChunkEnable[ExposureTime], each frame carries ChunkExposureTime (the
// exposure it was taken with). Lost packets are resent on request (GVCP PACKETRESEND, declared in
// the GVCP capability register) from the last 8 frames kept in memory. It answers GigE Vision
// discovery broadcasts (255.255.255.255:3956) on the loopback interface, so that Aravis's
// discovery (arv-tool-0.8, `irdist devices --discover`) finds it by name. Pixel formats: Mono8,
// Mono12, Mono12p (PFNC, LSB-first packed) and Mono16.
//
// Faults: whole frames dropped at drop_frame_rate, GVSP packets lost at lost_packet_ratio (first
// transmissions and resends alike), and ExposureTime writes applied late (acknowledged at once, but
// taking effect after a random delay up to a maximum, so that two quick writes may also land in the
// reverse order).

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "base/check.h"
#include "sim/rig_physics.h"
#include "sim/world.h"

namespace irdist::sim {

// The camera could not start (port taken, socket failure). The message says what to do.
class CameraServerError : public Error {
 public:
  using Error::Error;
};

// What the camera did for one frame it exposed, and its truth: the IRED's pose at the middle of
// the exposure (docs/virtual-rig.md, "Truth of a moving target").
struct FrameRecord {
  std::uint64_t index = 0;        // camera-side frame counter since Start (1, 2, ...)
  std::uint16_t block_id = 0;     // GVSP block id the frame was sent with (1..65535)
  double sim_time_s = 0.0;        // simulated time at the start of the exposure
  // The frame's GigE Vision timestamp (its leader's): the exposure's start on the world's clock
  // in ns (SimTimeToNs(sim_time_s)); mid-exposure = timestamp_ns + exposure_us * 1000 / 2.
  std::uint64_t timestamp_ns = 0;
  double exposure_us = 0.0;       // exposure the frame was taken with
  double slide_mm = 0.0;          // pose at the middle of the exposure (the frame's truth)
  double pan_deg = 0.0;
  double tilt_deg = 0.0;
  double theta_deg = 0.0;
  double slide_mm_s = 0.0;        // signed velocities at the middle of the exposure
  double pan_deg_s = 0.0;
  double tilt_deg_s = 0.0;
  // The truth came from the station's exact trajectory (sim/trajectory.h); false: no station
  // profile is known (a station of devices, a test that sets the pose), and the pose is the
  // World's as sampled at the exposure's start, velocities 0.
  bool truth_from_trajectory = false;
  double bias_ma = 0.0;
  double junction_rise_k = 0.0;
  bool moving = false;            // an axis moved during the exposure
  bool dropped = false;           // the frame was never sent (fault injection)
  std::string format;             // Mono8 / Mono12 / Mono16
};

// Counters of the control and stream channels.
struct CameraServerStats {
  std::uint64_t control_requests = 0;     // GVCP commands served
  std::uint64_t requests_during_frame = 0;  // of which while a frame was exposed or read out
  std::uint64_t resend_requests = 0;      // PACKETRESEND commands received
  std::uint64_t packets_resent = 0;       // GVSP packets sent again on request
  std::uint64_t packets_lost = 0;         // GVSP packets not sent (lost_packet_ratio)
  std::uint64_t triggers_queued = 0;      // triggers that arrived while the sensor was busy
  std::uint64_t triggers_ignored = 0;     // triggers beyond the queue, or with acquisition off
  std::uint64_t exposure_writes_delayed = 0;
  std::uint64_t controllers_expired = 0;  // control privileges released on heartbeat timeout
};

class CameraServer {
 public:
  CameraServer(World& world, const RigPhysics& physics);
  ~CameraServer();  // stops
  CameraServer(const CameraServer&) = delete;
  CameraServer& operator=(const CameraServer&) = delete;

  // Checks that UDP port 3956 on 127.0.0.1 is free, binds it, then starts the control and sensor
  // threads and connects the World's trigger line. Throws CameraServerError.
  void Start();
  // Stops both threads, closes the sockets and disconnects the trigger line. Idempotent; safe at
  // any moment (a client in the middle of a request or killed while connected).
  void Stop();
  bool running() const;

  std::string address() const { return "127.0.0.1"; }
  std::string serial() const;
  std::string device_id() const;  // as Aravis names it: "Aravis-Fake-<serial>"

  // Fault injection, effective from the next frame (or the next ExposureTime write).
  void SetDropFrameRate(double rate);
  void SetLostPacketRatio(double ratio);
  // Whether the camera resends packets (default true). Off, it declares no PACKETRESEND in its
  // GVCP capability register (read by the grabber when it configures the stream) and ignores the
  // command, as a camera without resend does.
  void SetPacketResend(bool enabled);
  // ExposureTime writes take effect after a random delay in [0, max_delay_ms] (host ms); 0 = at
  // once. Reads return the old value until then.
  void SetExposureWriteDelayMs(double max_delay_ms);

  // Observation (thread-safe).
  std::uint64_t FramesExposed() const;
  std::uint64_t FramesDropped() const;
  std::uint64_t LinePulsesAccepted() const;  // Line1 pulses that triggered (mode On, source Line1)
  std::vector<FrameRecord> RecentFrames() const;  // the last up to 1000 frames, oldest first
  CameraServerStats Stats() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace irdist::sim
