#pragma once
// The virtual camera's inside (sim-internal: included by sim/camera_server*.cc only): the register
// map's addresses and the state shared by the camera's three parts, each in its own file: the
// control channel (GVCP: register and memory access, discovery, controller privilege;
// camera_server_gvcp.cc), the stream channel (GVSP: leader, payload, trailer, resends;
// camera_server_gvsp.cc) and the sensor (exposure, readout, the frames kept;
// camera_server_sensor.cc). camera_server_device.cc starts and stops their threads, holds the
// register map and takes the triggers.

#include <arv.h>
#include <netinet/in.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <random>
#include <thread>
#include <vector>

#include "sim/camera_server.h"
#include "sim/renderer.h"

namespace irdist::sim {

using SteadyClock = std::chrono::steady_clock;

// Registers (ArvFakeCamera's bootstrap map, plus ours from sim/virtual_camera.xml).
inline constexpr guint32 kRegWidth = 0x100;
inline constexpr guint32 kRegHeight = 0x104;
inline constexpr guint32 kRegSensorHeight = 0x118;
inline constexpr guint32 kRegSensorWidth = 0x11c;
inline constexpr guint32 kRegExposureUs = 0x120;
inline constexpr guint32 kRegAcquisition = 0x124;
inline constexpr guint32 kRegPixelFormat = 0x128;
inline constexpr guint32 kRegOffsetX = 0x130;
inline constexpr guint32 kRegOffsetY = 0x134;
inline constexpr guint32 kRegFramePeriodUs = 0x138;
inline constexpr guint32 kRegTriggerMode = 0x300;
inline constexpr guint32 kRegTriggerSoftware = 0x30c;
inline constexpr guint32 kRegTriggerSource = 0x8000;
inline constexpr guint32 kRegDeviceTemperature = 0x8008;  // milli-degrees Celsius, signed
inline constexpr guint32 kRegBlackLevel = 0x800c;
inline constexpr guint32 kRegChunkModeActive = 0x8010;
inline constexpr guint32 kRegChunkEnableExposure = 0x8018;
inline constexpr guint32 kRegLutEnable = 0x801c;
inline constexpr guint32 kRegGvcpCapability = 0x934;
inline constexpr guint32 kRegHeartbeatMs = 0x938;
inline constexpr guint32 kRegControlPrivilege = 0xa00;
// GigE Vision 2.0 bootstrap: the primary application's UDP port and IPv4 address (0 = none), so a
// client refused control can say who holds it.
inline constexpr guint32 kRegPrimaryAppPort = 0xa10;
inline constexpr guint32 kRegPrimaryAppAddress = 0xa14;
inline constexpr guint32 kRegStreamPort = 0xd00;
inline constexpr guint32 kRegPacketSize = 0xd04;
inline constexpr guint32 kRegStreamAddress = 0xd18;
inline constexpr guint32 kSourceSoftware = 1;
inline constexpr guint32 kSourceLine1 = 2;
inline constexpr guint32 kPixelMono8 = 0x01080001;
inline constexpr guint32 kPixelMono12 = 0x01100005;
inline constexpr guint32 kPixelMono12p = 0x010c0047;  // PFNC: 12-bit, packed LSB-first
inline constexpr guint32 kPixelMono16 = 0x01100007;

// Big-endian fields of GVCP and GVSP packets.
inline void PutU16(std::vector<std::uint8_t>& out, std::uint16_t v) {
  out.push_back(static_cast<std::uint8_t>(v >> 8));
  out.push_back(static_cast<std::uint8_t>(v));
}
inline void PutU32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  PutU16(out, static_cast<std::uint16_t>(v >> 16));
  PutU16(out, static_cast<std::uint16_t>(v));
}
inline std::uint16_t GetU16(const std::uint8_t* p) {
  return static_cast<std::uint16_t>((p[0] << 8) | p[1]);
}
inline std::uint32_t GetU32(const std::uint8_t* p) {
  return (static_cast<std::uint32_t>(GetU16(p)) << 16) | GetU16(p + 2);
}

// Everything the sensor latches when a frame starts.
struct FrameSetup {
  double exposure_us = 0.0;
  guint32 pixel_format = kPixelMono8;
  int width = 0;
  int height = 0;
  int offset_x = 0;
  int offset_y = 0;
  double black_offset_dn = 0.0;
  double curve_gamma = 1.0;  // the LUT's and the fixed gamma's curve together (1 = linear)
  bool chunks = false;
  bool exposure_chunk = false;
  std::size_t packet_size = 1400;
  sockaddr_in destination{};
};

// One frame as sent, kept for resend requests.
struct SentFrame {
  std::uint16_t block_id = 0;
  std::vector<std::vector<std::uint8_t>> packets;  // leader, payload..., trailer
};

// An ExposureTime write held back by the fault knob.
struct PendingWrite {
  SteadyClock::time_point due;
  guint32 value = 0;
};

struct CameraServer::Impl {
  Impl(World& w, const RigPhysics& p) : world(w), physics(p), renderer(p) {
    drop_rate = p.camera.drop_frame_rate;
    lost_ratio = p.camera.lost_packet_ratio;
    write_delay_ms = p.camera.exposure_write_delay_ms;
    packet_resend = p.camera.packet_resend;
  }

  World& world;
  RigPhysics physics;
  Renderer renderer;

  // Register map: every access under reg_mutex.
  mutable std::mutex reg_mutex;
  ArvFakeCamera* fake = nullptr;
  sockaddr_in controller{};
  bool have_controller = false;
  SteadyClock::time_point controller_seen;
  std::vector<PendingWrite> pending_writes;

  // Sensor state: under state_mutex.
  std::mutex state_mutex;
  std::condition_variable wake;
  // Accepted triggers not started yet; a frame triggered while the sensor is idle starts (and
  // latches its settings) at the trigger, a queued one when the sensor becomes free.
  std::deque<std::optional<FrameSetup>> pending_triggers;
  bool busy = false;
  bool stopping = false;

  int control_fd = -1;
  int stream_fd = -1;
  // GigE Vision discovery is broadcast: a host's DISCOVERY_CMD to 255.255.255.255:3956 reaches
  // the camera on this socket; the acknowledge goes back from the control port.
  int discovery_fd = -1;
  std::atomic<bool> packet_resend{true};
  std::thread control_thread;
  std::thread sensor_thread;

  std::atomic<double> drop_rate{0.0};
  std::atomic<double> lost_ratio{0.0};
  std::atomic<double> write_delay_ms{0.0};
  std::mt19937_64 sensor_rng{1};   // sensor thread only
  std::mt19937_64 control_rng{2};  // control thread only
  std::uint64_t frame_counter = 0;  // sensor thread only
  std::uint16_t next_block_id = 1;  // sensor thread only

  mutable std::mutex mutex;  // records, counters, resend store
  std::deque<FrameRecord> records;
  std::deque<std::shared_ptr<const SentFrame>> sent;
  std::uint64_t exposed = 0;
  std::uint64_t dropped = 0;
  CameraServerStats stats;
  std::atomic<std::uint64_t> pulses_accepted{0};

  // --- register map and triggers (camera_server_device.cc) ---------------------------------------

  guint32 ReadLocked(guint32 address) const;
  void WriteLocked(guint32 address, guint32 value);
  guint32 Read(guint32 address) const;
  void Write(guint32 address, guint32 value);
  void InitRegisters();
  // A trigger from `source` (Software or Line1): starts a frame when the camera waits for that one.
  bool OfferTrigger(guint32 source);
  void OnLinePulse();

  // --- control channel: GVCP (camera_server_gvcp.cc) ---------------------------------------------

  static bool SameAddress(const sockaddr_in& a, const sockaddr_in& b);
  // Whether `from` may write: no controller yet, or it is the controller.
  bool MayWrite(const sockaddr_in& from) const;
  // After a command: a controller appears or leaves with the privilege register.
  void TrackController(const sockaddr_in& from);
  // No controller any more: privilege, primary application and acquisition cleared (reg_mutex held).
  void ReleaseControllerLocked();
  // A controller silent for longer than its heartbeat timeout has gone (crashed or killed): the
  // privilege is released and acquisition stopped, as a real camera does.
  void ExpireController();
  // A register write from the network: TriggerSoftware fires, delayed ExposureTime writes wait.
  void WriteRegisterFromNetwork(guint32 address, guint32 value);
  void ApplyDueWrites();
  std::vector<std::uint8_t> AckHeader(std::uint16_t status, std::uint16_t command,
                                      std::uint16_t length, std::uint16_t request_id) const;
  // Serves one GVCP command; returns the acknowledge to send (empty: none).
  std::vector<std::uint8_t> Serve(const std::uint8_t* packet, std::size_t size,
                                  const sockaddr_in& from, bool* fire_software_trigger);
  std::vector<std::uint8_t> ReadRegistersAck(std::uint16_t command, std::uint16_t request_id,
                                             const std::uint8_t* data, std::size_t length);
  std::vector<std::uint8_t> WriteRegistersAck(std::uint16_t command, std::uint16_t request_id,
                                              const std::uint8_t* data, std::size_t length,
                                              const sockaddr_in& from, bool* fire);
  std::vector<std::uint8_t> ReadMemoryAck(std::uint16_t command, std::uint16_t request_id,
                                          guint32 address, std::size_t count, bool with_address);
  std::vector<std::uint8_t> WriteMemoryAck(std::uint16_t command, std::uint16_t request_id,
                                           const std::uint8_t* data, std::size_t length,
                                           const sockaddr_in& from, bool* fire);
  void ControlLoop();
  void ServeOne(std::vector<std::uint8_t>& packet);
  // A broadcast command: only DISCOVERY_CMD is answered (GigE Vision), from the control port to
  // the sender.
  void ServeDiscovery(std::vector<std::uint8_t>& packet);

  // --- stream channel: GVSP packets and resends (camera_server_gvsp.cc) --------------------------

  bool Lose(std::mt19937_64& rng);
  void SendPacket(const std::vector<std::uint8_t>& packet, const sockaddr_in& to);
  // Answers a PACKETRESEND command (GigE Vision 1.x ids: 16-bit block, 24-bit packet ids).
  void Resend(std::uint32_t block, std::uint32_t first, std::uint32_t last);
  static std::vector<std::uint8_t> GvspHeader(std::uint16_t block_id, std::uint8_t format,
                                              std::uint32_t packet_id);
  static std::vector<std::uint8_t> Leader(std::uint16_t block_id, const FrameSetup& s,
                                          std::uint64_t timestamp_ns);
  // The frame's packets: leader, payload (image, then the chunks when active), trailer.
  static SentFrame Packetize(std::uint16_t block_id, const FrameSetup& s,
                             const std::vector<std::uint8_t>& payload, std::uint64_t timestamp_ns);
  // Appends the chunk layout read from the end: [image][image tag][exposure][exposure tag].
  static void AppendChunks(const FrameSetup& s, std::vector<std::uint8_t>& payload);
  void Transmit(const SentFrame& frame, const sockaddr_in& to);

  // --- sensor: latch, expose, read out, keep (camera_server_sensor.cc) ---------------------------

  FrameSetup LatchSetup();
  FrameSetup LatchSetupLocked() const;
  void SleepSim(double sim_s);
  // Renders the exposed image into `payload` (bytes as sent).
  FrameRecord Expose(const FrameSetup& s, std::uint64_t index, std::vector<std::uint8_t>& payload);
  FrameConditions ExposureConditions(double t0_s, double exposure_s,
                                     const PoseState& sampled_start) const;
  void RecordTruth(const FrameConditions& c, double t0_s, FrameRecord* record) const;
  // One frame: latch, expose, read out, send; then keep it for resend requests.
  void RunFrame(const std::optional<FrameSetup>& latched);
  void Keep(FrameRecord record, std::shared_ptr<const SentFrame> frame);
  // Waits for the next frame's start: a queued trigger (TriggerMode On) or the free-running
  // period. Returns false when stopping.
  bool WaitForFrameStart(SteadyClock::time_point* next_free_run,
                         std::optional<FrameSetup>* latched);
  void SensorLoop();
};

}  // namespace irdist::sim
