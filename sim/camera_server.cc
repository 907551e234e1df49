#include "sim/camera_server.h"

#include <arpa/inet.h>
#include <arv.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <random>
#include <thread>

#include "sim/renderer.h"

namespace irdist::sim {
namespace internal {
extern const char* const kVirtualCameraXml;
}  // namespace internal

namespace {

using SteadyClock = std::chrono::steady_clock;

// Registers (ArvFakeCamera's bootstrap map, plus ours from sim/virtual_camera.xml).
constexpr guint32 kRegWidth = 0x100;
constexpr guint32 kRegHeight = 0x104;
constexpr guint32 kRegSensorHeight = 0x118;
constexpr guint32 kRegSensorWidth = 0x11c;
constexpr guint32 kRegExposureUs = 0x120;
constexpr guint32 kRegAcquisition = 0x124;
constexpr guint32 kRegPixelFormat = 0x128;
constexpr guint32 kRegOffsetX = 0x130;
constexpr guint32 kRegOffsetY = 0x134;
constexpr guint32 kRegFramePeriodUs = 0x138;
constexpr guint32 kRegTriggerMode = 0x300;
constexpr guint32 kRegTriggerSoftware = 0x30c;
constexpr guint32 kRegTriggerSource = 0x8000;
constexpr guint32 kRegDeviceTemperature = 0x8008;  // milli-degrees Celsius, signed
constexpr guint32 kRegBlackLevel = 0x800c;
constexpr guint32 kRegChunkModeActive = 0x8010;
constexpr guint32 kRegChunkEnableExposure = 0x8018;
constexpr guint32 kRegGvcpCapability = 0x934;
constexpr guint32 kRegHeartbeatMs = 0x938;
constexpr guint32 kRegControlPrivilege = 0xa00;
constexpr guint32 kRegStreamPort = 0xd00;
constexpr guint32 kRegPacketSize = 0xd04;
constexpr guint32 kRegStreamAddress = 0xd18;
constexpr guint32 kCapabilityWriteMemory = 1u << 1;  // bit numbering as Aravis reads it
constexpr guint32 kCapabilityPacketResend = 1u << 2;
constexpr guint32 kSourceSoftware = 1;
constexpr guint32 kSourceLine1 = 2;
constexpr guint32 kPixelMono8 = 0x01080001;
constexpr guint32 kPixelMono12 = 0x01100005;
constexpr guint32 kPixelMono12p = 0x010c0047;  // PFNC: 12-bit, packed LSB-first
constexpr guint32 kPixelMono16 = 0x01100007;

// GVCP (GigE Vision control protocol) commands and status codes.
constexpr std::uint8_t kGvcpKey = 0x42;
constexpr std::uint16_t kCmdDiscovery = 0x0002;
constexpr std::uint16_t kCmdPacketResend = 0x0040;
constexpr std::uint16_t kCmdReadRegister = 0x0080;
constexpr std::uint16_t kCmdWriteRegister = 0x0082;
constexpr std::uint16_t kCmdReadMemory = 0x0084;
constexpr std::uint16_t kCmdWriteMemory = 0x0086;
constexpr std::uint16_t kStatusOk = 0x0000;
constexpr std::uint16_t kStatusNotImplemented = 0x8001;
constexpr std::uint16_t kStatusInvalidParameter = 0x8002;
constexpr std::uint16_t kStatusAccessDenied = 0x8006;
constexpr std::size_t kDiscoverySize = 0xf8;
constexpr std::size_t kMaxReadMemory = 536;

// GVSP (stream protocol) packet formats and payload types.
constexpr std::uint8_t kGvspLeader = 1;
constexpr std::uint8_t kGvspTrailer = 2;
constexpr std::uint8_t kGvspPayload = 3;
constexpr std::uint16_t kPayloadImage = 0x0001;
constexpr std::uint16_t kPayloadImageWithChunks = 0x4001;
constexpr std::size_t kGvspOverhead = 20 + 8 + 8;  // IP + UDP + GVSP headers
constexpr std::uint32_t kImageChunkId = 0x00000001;
constexpr std::uint32_t kExposureChunkId = 0x00001001;  // sim/virtual_camera.xml's ChunkID

constexpr int kGvcpPort = 3956;
constexpr std::size_t kRecordsKept = 1000;
constexpr std::size_t kFramesKeptForResend = 8;
constexpr int kTriggerQueue = 4;

void PutU16(std::vector<std::uint8_t>& out, std::uint16_t v) {
  out.push_back(static_cast<std::uint8_t>(v >> 8));
  out.push_back(static_cast<std::uint8_t>(v));
}
void PutU32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  PutU16(out, static_cast<std::uint16_t>(v >> 16));
  PutU16(out, static_cast<std::uint16_t>(v));
}
std::uint16_t GetU16(const std::uint8_t* p) {
  return static_cast<std::uint16_t>((p[0] << 8) | p[1]);
}
std::uint32_t GetU32(const std::uint8_t* p) {
  return (static_cast<std::uint32_t>(GetU16(p)) << 16) | GetU16(p + 2);
}

// A UDP socket bound to address:port (0 = any port); -1 with `why` set on failure.
int BindUdp(std::uint32_t address, int port, std::string* why) {
  const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) {
    *why = std::string("socket(): ") + std::strerror(errno);
    return -1;
  }
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<std::uint16_t>(port));
  addr.sin_addr.s_addr = htonl(address);
  if (::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) != 0) {
    *why = std::strerror(errno);
    ::close(fd);
    return -1;
  }
  return fd;
}

int BindLoopbackUdp(int port, std::string* why) { return BindUdp(INADDR_LOOPBACK, port, why); }

PixelFormat FormatOf(guint32 pixel_format) {
  switch (pixel_format) {
    case kPixelMono12:
    case kPixelMono12p:
      return PixelFormat::kMono12;
    case kPixelMono16:
      return PixelFormat::kMono16;
    case kPixelMono8:
    default:
      return PixelFormat::kMono8;
  }
}

// GenICam PFNC Mono12p: the pixels as one bit stream, each pixel's bit 0 first, bit k of the
// stream being bit k % 8 of byte k / 8: two pixels a, b in three bytes
// [a bits 0-7][b bits 0-3 << 4 | a bits 8-11][b bits 4-11].
void PackMono12p(const cv::Mat& pixels, std::uint8_t* out) {
  const std::size_t count = pixels.total();
  const auto* p = pixels.ptr<std::uint16_t>();
  for (std::size_t i = 0; i < count; i += 2) {
    const unsigned a = p[i] & 0xfffu;
    const unsigned b = i + 1 < count ? p[i + 1] & 0xfffu : 0u;
    *out++ = static_cast<std::uint8_t>(a & 0xffu);
    *out++ = static_cast<std::uint8_t>((a >> 8) | ((b & 0xfu) << 4));
    if (i + 1 < count) *out++ = static_cast<std::uint8_t>(b >> 4);
  }
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

}  // namespace

struct CameraServer::Impl {
  Impl(World& w, const RigPhysics& p) : world(w), physics(p), renderer(p) {
    drop_rate = p.camera.drop_frame_rate;
    lost_ratio = p.camera.lost_packet_ratio;
    write_delay_ms = p.camera.exposure_write_delay_ms;
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

  // --- register map ------------------------------------------------------------------------------

  guint32 ReadLocked(guint32 address) const {
    guint32 value = 0;
    if (fake == nullptr || !arv_fake_camera_read_register(fake, address, &value)) return 0;
    return value;
  }
  void WriteLocked(guint32 address, guint32 value) {
    if (fake != nullptr) arv_fake_camera_write_register(fake, address, value);
  }
  guint32 Read(guint32 address) const {
    std::lock_guard<std::mutex> lock(reg_mutex);
    return ReadLocked(address);
  }
  void Write(guint32 address, guint32 value) {
    std::lock_guard<std::mutex> lock(reg_mutex);
    WriteLocked(address, value);
  }

  // --- triggers ----------------------------------------------------------------------------------

  // A trigger from `source` (Software or Line1): starts a frame when the camera waits for that one.
  bool OfferTrigger(guint32 source) {
    std::lock_guard<std::mutex> reg_lock(reg_mutex);
    if (ReadLocked(kRegTriggerMode) != 1 || ReadLocked(kRegTriggerSource) != source) return false;
    const bool acquiring = ReadLocked(kRegAcquisition) != 0;
    std::lock_guard<std::mutex> lock(state_mutex);
    std::lock_guard<std::mutex> count_lock(mutex);
    if (!acquiring || pending_triggers.size() >= static_cast<std::size_t>(kTriggerQueue)) {
      ++stats.triggers_ignored;
      return false;
    }
    if (busy || !pending_triggers.empty()) {
      ++stats.triggers_queued;
      pending_triggers.push_back(std::nullopt);
    } else {
      pending_triggers.push_back(LatchSetupLocked());
    }
    wake.notify_all();
    return true;
  }

  void OnLinePulse() {
    if (OfferTrigger(kSourceLine1)) ++pulses_accepted;
  }

  // --- control channel ---------------------------------------------------------------------------

  static bool SameAddress(const sockaddr_in& a, const sockaddr_in& b) {
    return a.sin_addr.s_addr == b.sin_addr.s_addr && a.sin_port == b.sin_port;
  }

  // Whether `from` may write: no controller yet, or it is the controller.
  bool MayWrite(const sockaddr_in& from) const {
    return !have_controller || SameAddress(from, controller);
  }

  // After a command: a controller appears or leaves with the privilege register.
  void TrackController(const sockaddr_in& from) {
    const bool privileged = ReadLocked(kRegControlPrivilege) != 0;
    if (!have_controller && privileged) {
      have_controller = true;
      controller = from;
      controller_seen = SteadyClock::now();
    } else if (have_controller && !privileged) {
      have_controller = false;
      WriteLocked(kRegAcquisition, 0);
    }
  }

  // A controller silent for longer than its heartbeat timeout has gone (crashed or killed): the
  // privilege is released and acquisition stopped, as a real camera does.
  void ExpireController() {
    std::lock_guard<std::mutex> lock(reg_mutex);
    if (!have_controller) return;
    const auto timeout = std::chrono::milliseconds(ReadLocked(kRegHeartbeatMs));
    if (SteadyClock::now() - controller_seen <= timeout) return;
    have_controller = false;
    WriteLocked(kRegControlPrivilege, 0);
    WriteLocked(kRegAcquisition, 0);
    std::lock_guard<std::mutex> count_lock(mutex);
    ++stats.controllers_expired;
  }

  // A register write from the network: TriggerSoftware fires, delayed ExposureTime writes wait.
  void WriteRegisterFromNetwork(guint32 address, guint32 value) {
    if (address == kRegExposureUs && write_delay_ms.load() > 0.0) {
      const double delay_ms =
          std::uniform_real_distribution<double>(0.0, write_delay_ms.load())(control_rng);
      pending_writes.push_back(
          {SteadyClock::now() + std::chrono::microseconds(std::lround(delay_ms * 1000)), value});
      std::lock_guard<std::mutex> count_lock(mutex);
      ++stats.exposure_writes_delayed;
      return;
    }
    WriteLocked(address, value);
  }

  void ApplyDueWrites() {
    std::lock_guard<std::mutex> lock(reg_mutex);
    const auto now = SteadyClock::now();
    for (auto it = pending_writes.begin(); it != pending_writes.end();) {
      if (it->due <= now) {
        WriteLocked(kRegExposureUs, it->value);
        it = pending_writes.erase(it);
      } else {
        ++it;
      }
    }
  }

  std::vector<std::uint8_t> AckHeader(std::uint16_t status, std::uint16_t command,
                                      std::uint16_t length, std::uint16_t request_id) const {
    std::vector<std::uint8_t> ack;
    PutU16(ack, status);
    PutU16(ack, static_cast<std::uint16_t>(command + 1));
    PutU16(ack, length);
    PutU16(ack, request_id);
    return ack;
  }

  // Serves one GVCP command; returns the acknowledge to send (empty: none).
  std::vector<std::uint8_t> Serve(const std::uint8_t* packet, std::size_t size,
                                  const sockaddr_in& from, bool* fire_software_trigger) {
    if (size < 8 || packet[0] != kGvcpKey) return {};
    const std::uint16_t command = GetU16(packet + 2);
    const std::uint16_t length = GetU16(packet + 4);
    const std::uint16_t request_id = GetU16(packet + 6);
    const std::uint8_t* data = packet + 8;
    if (length > size - 8) return AckHeader(kStatusInvalidParameter, command, 0, request_id);
    if (command == kCmdPacketResend) {
      // A camera without resend does not know the command (GVCP: no acknowledge is ever sent).
      if (packet_resend && length >= 12) Resend(GetU32(data), GetU32(data + 4), GetU32(data + 8));
      return {};
    }
    std::lock_guard<std::mutex> lock(reg_mutex);
    // Any command from the controller is a heartbeat (GigE Vision: the primary application's
    // control traffic keeps its privilege alive).
    if (have_controller && SameAddress(from, controller)) controller_seen = SteadyClock::now();
    std::vector<std::uint8_t> ack;
    switch (command) {
      case kCmdDiscovery:
        ack = ReadMemoryAck(command, request_id, 0, kDiscoverySize, false);
        break;
      case kCmdReadRegister:
        ack = ReadRegistersAck(command, request_id, data, length);
        break;
      case kCmdWriteRegister:
        ack = WriteRegistersAck(command, request_id, data, length, from, fire_software_trigger);
        break;
      case kCmdReadMemory:
        ack = length >= 8 ? ReadMemoryAck(command, request_id, GetU32(data), GetU16(data + 6), true)
                          : AckHeader(kStatusInvalidParameter, command, 0, request_id);
        break;
      case kCmdWriteMemory:
        ack = WriteMemoryAck(command, request_id, data, length, from, fire_software_trigger);
        break;
      default:
        ack = AckHeader(kStatusNotImplemented, command, 0, request_id);
        break;
    }
    TrackController(from);
    return ack;
  }

  std::vector<std::uint8_t> ReadRegistersAck(std::uint16_t command, std::uint16_t request_id,
                                             const std::uint8_t* data, std::size_t length) {
    const std::size_t count = length / 4;
    std::vector<std::uint8_t> ack =
        AckHeader(kStatusOk, command, static_cast<std::uint16_t>(count * 4), request_id);
    for (std::size_t i = 0; i < count; ++i) PutU32(ack, ReadLocked(GetU32(data + 4 * i)));
    return ack;
  }

  std::vector<std::uint8_t> WriteRegistersAck(std::uint16_t command, std::uint16_t request_id,
                                              const std::uint8_t* data, std::size_t length,
                                              const sockaddr_in& from, bool* fire) {
    if (!MayWrite(from)) return AckHeader(kStatusAccessDenied, command, 4, request_id);
    const std::size_t count = length / 8;
    for (std::size_t i = 0; i < count; ++i) {
      const guint32 address = GetU32(data + 8 * i);
      const guint32 value = GetU32(data + 8 * i + 4);
      if (address == kRegTriggerSoftware) *fire = true;
      WriteRegisterFromNetwork(address, value);
    }
    std::vector<std::uint8_t> ack = AckHeader(kStatusOk, command, 4, request_id);
    PutU16(ack, 0);
    PutU16(ack, static_cast<std::uint16_t>(count));
    return ack;
  }

  std::vector<std::uint8_t> ReadMemoryAck(std::uint16_t command, std::uint16_t request_id,
                                          guint32 address, std::size_t count, bool with_address) {
    if (count > kMaxReadMemory || count % 4 != 0) {
      return AckHeader(kStatusInvalidParameter, command, 0, request_id);
    }
    std::vector<std::uint8_t> bytes(count, 0);
    if (fake != nullptr) arv_fake_camera_read_memory(fake, address, count, bytes.data());
    const std::size_t length = count + (with_address ? 4 : 0);
    std::vector<std::uint8_t> ack =
        AckHeader(kStatusOk, command, static_cast<std::uint16_t>(length), request_id);
    if (with_address) PutU32(ack, address);
    ack.insert(ack.end(), bytes.begin(), bytes.end());
    return ack;
  }

  std::vector<std::uint8_t> WriteMemoryAck(std::uint16_t command, std::uint16_t request_id,
                                           const std::uint8_t* data, std::size_t length,
                                           const sockaddr_in& from, bool* fire) {
    if (length < 4) return AckHeader(kStatusInvalidParameter, command, 0, request_id);
    if (!MayWrite(from)) return AckHeader(kStatusAccessDenied, command, 4, request_id);
    const guint32 address = GetU32(data);
    const std::size_t count = length - 4;
    if (count == 4 && (address == kRegExposureUs || address == kRegTriggerSoftware)) {
      if (address == kRegTriggerSoftware) *fire = true;
      WriteRegisterFromNetwork(address, GetU32(data + 4));
    } else if (fake != nullptr) {
      arv_fake_camera_write_memory(fake, address, static_cast<guint32>(count), data + 4);
    }
    std::vector<std::uint8_t> ack = AckHeader(kStatusOk, command, 4, request_id);
    PutU16(ack, 0);
    PutU16(ack, static_cast<std::uint16_t>(count));
    return ack;
  }

  void ControlLoop() {
    std::vector<std::uint8_t> packet(2048);
    while (true) {
      {
        std::lock_guard<std::mutex> lock(state_mutex);
        if (stopping) return;
      }
      pollfd fds[2] = {{control_fd, POLLIN, 0}, {discovery_fd, POLLIN, 0}};
      const int events = ::poll(fds, 2, 5);
      if (events > 0 && (fds[0].revents & POLLIN) != 0) ServeOne(packet);
      if (events > 0 && (fds[1].revents & POLLIN) != 0) ServeDiscovery(packet);
      ApplyDueWrites();
      ExpireController();
    }
  }

  void ServeOne(std::vector<std::uint8_t>& packet) {
    sockaddr_in from{};
    socklen_t from_size = sizeof(from);
    const ssize_t got = ::recvfrom(control_fd, packet.data(), packet.size(), 0,
                                   reinterpret_cast<sockaddr*>(&from), &from_size);
    if (got <= 0) return;
    bool fire = false;
    const std::vector<std::uint8_t> ack =
        Serve(packet.data(), static_cast<std::size_t>(got), from, &fire);
    if (!ack.empty()) {
      // A client gone meanwhile makes this fail; a camera does not care.
      (void)::sendto(control_fd, ack.data(), ack.size(), 0, reinterpret_cast<sockaddr*>(&from),
                     from_size);
    }
    {
      std::lock_guard<std::mutex> lock(state_mutex);
      std::lock_guard<std::mutex> count_lock(mutex);
      ++stats.control_requests;
      if (busy) ++stats.requests_during_frame;
    }
    if (fire) OfferTrigger(kSourceSoftware);
  }

  // A broadcast command: only DISCOVERY_CMD is answered (GigE Vision), from the control port to
  // the sender.
  void ServeDiscovery(std::vector<std::uint8_t>& packet) {
    sockaddr_in from{};
    socklen_t from_size = sizeof(from);
    const ssize_t got = ::recvfrom(discovery_fd, packet.data(), packet.size(), 0,
                                   reinterpret_cast<sockaddr*>(&from), &from_size);
    if (got < 8 || packet[0] != kGvcpKey || GetU16(packet.data() + 2) != kCmdDiscovery) return;
    bool fire = false;
    const std::vector<std::uint8_t> ack =
        Serve(packet.data(), static_cast<std::size_t>(got), from, &fire);
    // A host gone meanwhile makes this fail; a camera does not care.
    (void)::sendto(control_fd, ack.data(), ack.size(), 0, reinterpret_cast<sockaddr*>(&from),
                   from_size);
  }

  // --- stream channel ----------------------------------------------------------------------------

  bool Lose(std::mt19937_64& rng) {
    return std::uniform_real_distribution<double>(0.0, 1.0)(rng) < lost_ratio.load();
  }

  void SendPacket(const std::vector<std::uint8_t>& packet, const sockaddr_in& to) {
    if (ntohl(to.sin_addr.s_addr) >> 24 != 127 || to.sin_port == 0) return;  // loopback only
    (void)::sendto(stream_fd, packet.data(), packet.size(), 0,
                   reinterpret_cast<const sockaddr*>(&to), sizeof(to));
  }

  // Answers a PACKETRESEND command (GigE Vision 1.x ids: 16-bit block, 24-bit packet ids).
  void Resend(std::uint32_t block, std::uint32_t first, std::uint32_t last) {
    first &= 0xffffff;
    last &= 0xffffff;
    sockaddr_in to{};
    {
      std::lock_guard<std::mutex> lock(reg_mutex);
      to.sin_family = AF_INET;
      to.sin_addr.s_addr = htonl(ReadLocked(kRegStreamAddress));
      to.sin_port = htons(static_cast<std::uint16_t>(ReadLocked(kRegStreamPort) & 0xffff));
    }
    std::vector<std::vector<std::uint8_t>> packets;
    {
      std::lock_guard<std::mutex> lock(mutex);
      ++stats.resend_requests;
      for (const auto& frame : sent) {
        if (frame->block_id != (block & 0xffff)) continue;
        for (std::uint32_t id = first; id <= last && id < frame->packets.size(); ++id) {
          packets.push_back(frame->packets[id]);
        }
      }
    }
    std::uint64_t resent = 0, lost = 0;
    for (const auto& packet : packets) {
      if (Lose(control_rng)) {
        ++lost;
        continue;
      }
      SendPacket(packet, to);
      ++resent;
    }
    std::lock_guard<std::mutex> lock(mutex);
    stats.packets_resent += resent;
    stats.packets_lost += lost;
  }

  static std::vector<std::uint8_t> GvspHeader(std::uint16_t block_id, std::uint8_t format,
                                              std::uint32_t packet_id) {
    std::vector<std::uint8_t> packet;
    PutU16(packet, 0);
    PutU16(packet, block_id);
    PutU32(packet, (static_cast<std::uint32_t>(format) << 24) | (packet_id & 0xffffff));
    return packet;
  }

  static std::vector<std::uint8_t> Leader(std::uint16_t block_id, const FrameSetup& s,
                                          std::uint64_t timestamp_ns) {
    std::vector<std::uint8_t> packet = GvspHeader(block_id, kGvspLeader, 0);
    PutU16(packet, 0);
    PutU16(packet, s.chunks ? kPayloadImageWithChunks : kPayloadImage);
    PutU32(packet, static_cast<std::uint32_t>(timestamp_ns >> 32));
    PutU32(packet, static_cast<std::uint32_t>(timestamp_ns));
    PutU32(packet, s.pixel_format);
    for (int v : {s.width, s.height, s.offset_x, s.offset_y}) PutU32(packet, static_cast<guint32>(v));
    PutU16(packet, 0);
    PutU16(packet, 0);
    return packet;
  }

  // The frame's packets: leader, payload (image, then the chunks when active), trailer.
  static SentFrame Packetize(std::uint16_t block_id, const FrameSetup& s,
                             const std::vector<std::uint8_t>& payload, std::uint64_t timestamp_ns) {
    SentFrame frame;
    frame.block_id = block_id;
    frame.packets.push_back(Leader(block_id, s, timestamp_ns));
    const std::size_t per_packet = std::max<std::size_t>(s.packet_size - kGvspOverhead, 64);
    std::uint32_t packet_id = 1;
    for (std::size_t offset = 0; offset < payload.size(); offset += per_packet, ++packet_id) {
      std::vector<std::uint8_t> packet = GvspHeader(block_id, kGvspPayload, packet_id);
      const std::size_t n = std::min(per_packet, payload.size() - offset);
      packet.insert(packet.end(), payload.begin() + static_cast<std::ptrdiff_t>(offset),
                    payload.begin() + static_cast<std::ptrdiff_t>(offset + n));
      frame.packets.push_back(std::move(packet));
    }
    std::vector<std::uint8_t> trailer = GvspHeader(block_id, kGvspTrailer, packet_id);
    PutU16(trailer, 0);
    PutU16(trailer, s.chunks ? kPayloadImageWithChunks : kPayloadImage);
    PutU32(trailer, static_cast<std::uint32_t>(s.height));
    frame.packets.push_back(std::move(trailer));
    return frame;
  }

  // Appends the chunk layout read from the end: [image][image tag][exposure][exposure tag].
  static void AppendChunks(const FrameSetup& s, std::vector<std::uint8_t>& payload) {
    const std::uint32_t image_bytes = static_cast<std::uint32_t>(payload.size());
    PutU32(payload, kImageChunkId);
    PutU32(payload, image_bytes);
    if (!s.exposure_chunk) return;
    std::uint64_t bits = 0;
    static_assert(sizeof(bits) == sizeof(s.exposure_us), "IEEE double");
    std::memcpy(&bits, &s.exposure_us, sizeof(bits));
    PutU32(payload, static_cast<std::uint32_t>(bits >> 32));
    PutU32(payload, static_cast<std::uint32_t>(bits));
    PutU32(payload, kExposureChunkId);
    PutU32(payload, 8);
  }

  // --- sensor ------------------------------------------------------------------------------------

  FrameSetup LatchSetup() {
    std::lock_guard<std::mutex> lock(reg_mutex);
    return LatchSetupLocked();
  }

  FrameSetup LatchSetupLocked() const {
    FrameSetup s;
    s.exposure_us = static_cast<double>(ReadLocked(kRegExposureUs));
    s.pixel_format = ReadLocked(kRegPixelFormat);
    s.width = static_cast<int>(ReadLocked(kRegWidth));
    s.height = static_cast<int>(ReadLocked(kRegHeight));
    s.offset_x = static_cast<int>(ReadLocked(kRegOffsetX));
    s.offset_y = static_cast<int>(ReadLocked(kRegOffsetY));
    s.black_offset_dn = static_cast<double>(ReadLocked(kRegBlackLevel));
    s.chunks = ReadLocked(kRegChunkModeActive) != 0;
    s.exposure_chunk = s.chunks && ReadLocked(kRegChunkEnableExposure) != 0;
    s.packet_size = std::max<guint32>(ReadLocked(kRegPacketSize) & 0xffff, 576);
    s.destination.sin_family = AF_INET;
    s.destination.sin_addr.s_addr = htonl(ReadLocked(kRegStreamAddress));
    s.destination.sin_port = htons(static_cast<std::uint16_t>(ReadLocked(kRegStreamPort) & 0xffff));
    return s;
  }

  void SleepSim(double sim_s) {
    if (sim_s <= 0.0) return;
    std::unique_lock<std::mutex> lock(state_mutex);
    wake.wait_for(lock, world.clock().HostDuration(sim_s), [this] { return stopping; });
  }

  // Renders the exposed image into `payload` (bytes as sent).
  FrameRecord Expose(const FrameSetup& s, std::uint64_t index, std::vector<std::uint8_t>& payload) {
    const PixelFormat format = FormatOf(s.pixel_format);
    const double exposure_s = s.exposure_us * 1e-6;
    FrameConditions c;
    const double t0 = world.clock().Now();
    c.pose_start = world.Pose();
    c.exposure_s = exposure_s;
    c.black_offset_dn = s.black_offset_dn;
    SleepSim(exposure_s);
    c.pose_end = world.Pose();
    c.junction_rise_k =
        renderer.scene().JunctionRiseK(world.CurrentHistory(), t0 + 0.5 * exposure_s);
    const std::size_t pixels = static_cast<std::size_t>(std::max(s.width, 0)) *
                               static_cast<std::size_t>(std::max(s.height, 0));
    if (s.pixel_format == kPixelMono12p) {
      cv::Mat out(s.height, s.width, FormatCvType(format));
      if (pixels > 0) renderer.Render(c, index, format, cv::Point(s.offset_x, s.offset_y), out);
      payload.assign((pixels * 12 + 7) / 8, 0);
      if (pixels > 0) PackMono12p(out, payload.data());
    } else {
      const std::size_t bytes_per_pixel = format == PixelFormat::kMono8 ? 1 : 2;
      payload.assign(pixels * bytes_per_pixel, 0);
      if (pixels > 0) {
        cv::Mat out(s.height, s.width, FormatCvType(format), payload.data());
        renderer.Render(c, index, format, cv::Point(s.offset_x, s.offset_y), out);
      }
    }
    FrameRecord record;
    record.index = index;
    record.sim_time_s = t0;
    record.exposure_us = s.exposure_us;
    record.slide_mm = c.pose_start.slide_mm;
    record.theta_deg = c.pose_start.ThetaDeg();
    record.bias_ma = c.pose_start.bias_ma;
    record.junction_rise_k = c.junction_rise_k;
    record.moving = c.pose_start.moving || c.pose_end.moving;
    record.format = s.pixel_format == kPixelMono12p ? "Mono12p" : PixelFormatName(format);
    return record;
  }

  // One frame: latch, expose, read out, send; then keep it for resend requests.
  void RunFrame(const std::optional<FrameSetup>& latched) {
    const auto host_start = SteadyClock::now();
    const FrameSetup s = latched.has_value() ? *latched : LatchSetup();
    const std::uint64_t index = ++frame_counter;
    const std::uint16_t block_id = next_block_id;
    next_block_id = static_cast<std::uint16_t>(next_block_id == 0xffff ? 1 : next_block_id + 1);
    const auto timestamp_ns = static_cast<std::uint64_t>(
        std::chrono::duration_cast<std::chrono::nanoseconds>(host_start.time_since_epoch()).count());
    std::vector<std::uint8_t> payload;
    FrameRecord record = Expose(s, index, payload);
    record.block_id = block_id;
    if (s.chunks) AppendChunks(s, payload);
    const bool drop = std::uniform_real_distribution<double>(0.0, 1.0)(sensor_rng) < drop_rate;
    record.dropped = drop;
    Write(kRegDeviceTemperature, static_cast<guint32>(static_cast<gint32>(
                                     std::lround(physics.sensor.temperature_c * 1000))));
    auto frame = std::make_shared<const SentFrame>(Packetize(block_id, s, payload, timestamp_ns));
    // Readout: the frame leaves the camera `readout_ms` after the exposure ends.
    const double spent_sim_s =
        std::chrono::duration<double>(SteadyClock::now() - host_start).count() *
        world.clock().time_scale();
    SleepSim(s.exposure_us * 1e-6 + physics.camera.readout_ms * 1e-3 - spent_sim_s);
    // Recorded (and kept for resend requests) before it leaves, so that whoever received it
    // finds its record.
    Keep(std::move(record), drop ? nullptr : frame);
    if (!drop) Transmit(*frame, s.destination);
  }

  void Transmit(const SentFrame& frame, const sockaddr_in& to) {
    std::uint64_t lost = 0;
    for (const auto& packet : frame.packets) {
      if (Lose(sensor_rng)) {
        ++lost;
        continue;
      }
      SendPacket(packet, to);
    }
    std::lock_guard<std::mutex> lock(mutex);
    stats.packets_lost += lost;
  }

  void Keep(FrameRecord record, std::shared_ptr<const SentFrame> frame) {
    std::lock_guard<std::mutex> lock(mutex);
    ++exposed;
    if (record.dropped) ++dropped;
    records.push_back(std::move(record));
    if (records.size() > kRecordsKept) records.pop_front();
    if (frame != nullptr) sent.push_back(std::move(frame));
    if (sent.size() > kFramesKeptForResend) sent.pop_front();
  }

  // Waits for the next frame's start: a queued trigger (TriggerMode On) or the free-running
  // period. Returns false when stopping.
  bool WaitForFrameStart(SteadyClock::time_point* next_free_run,
                         std::optional<FrameSetup>* latched) {
    while (true) {
      const bool triggered = Read(kRegTriggerMode) == 1;
      const bool acquiring = Read(kRegAcquisition) != 0;
      const auto period = std::chrono::microseconds(std::max<guint32>(Read(kRegFramePeriodUs), 1000));
      std::unique_lock<std::mutex> lock(state_mutex);
      if (stopping) return false;
      if (!acquiring) pending_triggers.clear();
      if (acquiring && triggered && !pending_triggers.empty()) {
        *latched = pending_triggers.front();
        pending_triggers.pop_front();
        busy = true;
        return true;
      }
      const auto now = SteadyClock::now();
      if (acquiring && !triggered && now >= *next_free_run) {
        *next_free_run = std::max(*next_free_run + period, now);
        latched->reset();
        busy = true;
        return true;
      }
      if (!acquiring || triggered) *next_free_run = now + period;
      wake.wait_for(lock, std::chrono::milliseconds(5));
    }
  }

  void SensorLoop() {
    auto next_free_run = SteadyClock::now();
    std::optional<FrameSetup> latched;
    while (WaitForFrameStart(&next_free_run, &latched)) {
      RunFrame(latched);
      std::lock_guard<std::mutex> lock(state_mutex);
      busy = false;
    }
  }

  void InitRegisters() {
    const SensorOptions& s = physics.sensor;
    std::lock_guard<std::mutex> lock(reg_mutex);
    WriteLocked(kRegSensorWidth, static_cast<guint32>(s.width_px));
    WriteLocked(kRegSensorHeight, static_cast<guint32>(s.height_px));
    WriteLocked(kRegWidth, static_cast<guint32>(s.width_px));
    WriteLocked(kRegHeight, static_cast<guint32>(s.height_px));
    WriteLocked(kRegTriggerSource, kSourceLine1);
    WriteLocked(kRegBlackLevel, 0);
    WriteLocked(kRegChunkModeActive, 0);
    WriteLocked(kRegChunkEnableExposure, 0);
    WriteLocked(kRegGvcpCapability,
                kCapabilityWriteMemory | (packet_resend ? kCapabilityPacketResend : 0u));
    WriteLocked(kRegDeviceTemperature,
                static_cast<guint32>(static_cast<gint32>(std::lround(s.temperature_c * 1000))));
  }
};

CameraServer::CameraServer(World& world, const RigPhysics& physics)
    : impl_(std::make_unique<Impl>(world, physics)) {
  std::string why;
  IRDIST_CHECK(physics.IsValid(&why), why);
  impl_->sensor_rng.seed(physics.sensor.seed * 7919 + 17);
  impl_->control_rng.seed(physics.sensor.seed * 104729 + 3);
}

CameraServer::~CameraServer() { Stop(); }

bool CameraServer::running() const { return impl_->control_fd >= 0; }
std::string CameraServer::serial() const { return impl_->physics.camera.serial; }
std::string CameraServer::device_id() const { return "Aravis-Fake-" + serial(); }

namespace {

// Aravis's register map loads the GenICam XML from a file: the compiled-in copy goes to a private
// temporary file, removed as soon as the map has read it.
ArvFakeCamera* NewRegisterMap(const std::string& serial) {
  char path[] = "/tmp/irdist-virtual-camera-XXXXXX.xml";
  const int fd = ::mkstemps(path, 4);
  if (fd < 0) {
    throw CameraServerError(std::string("virtual camera: cannot create a temporary file in /tmp "
                                        "for its GenICam XML: ") + std::strerror(errno));
  }
  const std::string xml(internal::kVirtualCameraXml);
  const bool written = ::write(fd, xml.data(), xml.size()) == static_cast<ssize_t>(xml.size());
  ::close(fd);
  ArvFakeCamera* fake = written ? arv_fake_camera_new_full(serial.c_str(), path) : nullptr;
  ::unlink(path);
  if (!written) throw CameraServerError(std::string("virtual camera: cannot write ") + path);
  if (fake == nullptr) throw CameraServerError("virtual camera: Aravis refused its GenICam XML");
  GInetAddress* loopback = g_inet_address_new_loopback(G_SOCKET_FAMILY_IPV4);
  arv_fake_camera_set_inet_address(fake, loopback);
  g_object_unref(loopback);
  return fake;
}

}  // namespace

void CameraServer::Start() {
  Impl& d = *impl_;
  if (d.control_fd >= 0) return;
  std::string why;
  const int control_fd = BindLoopbackUdp(kGvcpPort, &why);
  if (control_fd < 0) {
    throw CameraServerError(
        "virtual camera: UDP port 3956 on 127.0.0.1 is already in use (" + why +
        "): another GigE Vision fake camera (irdist sim, arv-fake-gv-camera-0.8 or a test) is "
        "running on this host; stop it first (only one fake camera can serve 127.0.0.1)");
  }
  const int stream_fd = BindLoopbackUdp(0, &why);
  if (stream_fd < 0) {
    ::close(control_fd);
    throw CameraServerError("virtual camera: cannot open its stream socket: " + why);
  }
  const int discovery_fd = BindUdp(INADDR_BROADCAST, kGvcpPort, &why);
  if (discovery_fd < 0) {
    ::close(control_fd);
    ::close(stream_fd);
    throw CameraServerError("virtual camera: cannot listen for GigE Vision discovery on "
                            "255.255.255.255:3956 (" + why + "): stop the other GigE Vision "
                            "device or fake camera running on this host");
  }
  try {
    d.fake = NewRegisterMap(d.physics.camera.serial);
  } catch (...) {
    ::close(control_fd);
    ::close(stream_fd);
    ::close(discovery_fd);
    throw;
  }
  d.InitRegisters();
  d.control_fd = control_fd;
  d.stream_fd = stream_fd;
  d.discovery_fd = discovery_fd;
  d.stopping = false;
  d.control_thread = std::thread([&d] { d.ControlLoop(); });
  d.sensor_thread = std::thread([&d] { d.SensorLoop(); });
  Impl* impl = impl_.get();
  d.world.SetTriggerSink([impl] { impl->OnLinePulse(); });
}

void CameraServer::Stop() {
  Impl& d = *impl_;
  if (d.control_fd < 0) return;
  d.world.SetTriggerSink(nullptr);
  {
    std::lock_guard<std::mutex> lock(d.state_mutex);
    d.stopping = true;
  }
  d.wake.notify_all();
  if (d.control_thread.joinable()) d.control_thread.join();
  if (d.sensor_thread.joinable()) d.sensor_thread.join();
  ::close(d.control_fd);
  ::close(d.stream_fd);
  ::close(d.discovery_fd);
  d.control_fd = -1;
  d.stream_fd = -1;
  d.discovery_fd = -1;
  std::lock_guard<std::mutex> lock(d.reg_mutex);
  if (d.fake != nullptr) g_object_unref(d.fake);
  d.fake = nullptr;
  d.have_controller = false;
  d.pending_writes.clear();
}

void CameraServer::SetDropFrameRate(double rate) {
  IRDIST_CHECK(rate >= 0.0 && rate <= 1.0, "drop rate must lie in [0, 1]");
  impl_->drop_rate = rate;
}

void CameraServer::SetLostPacketRatio(double ratio) {
  IRDIST_CHECK(ratio >= 0.0 && ratio <= 1.0, "lost packet ratio must lie in [0, 1]");
  impl_->lost_ratio = ratio;
}

void CameraServer::SetPacketResend(bool enabled) {
  impl_->packet_resend = enabled;
  std::lock_guard<std::mutex> lock(impl_->reg_mutex);
  const guint32 capability = impl_->ReadLocked(kRegGvcpCapability);
  impl_->WriteLocked(kRegGvcpCapability, enabled ? capability | kCapabilityPacketResend
                                                 : capability & ~kCapabilityPacketResend);
}

void CameraServer::SetExposureWriteDelayMs(double max_delay_ms) {
  IRDIST_CHECK(max_delay_ms >= 0.0 && std::isfinite(max_delay_ms),
               "exposure write delay must be >= 0 ms");
  impl_->write_delay_ms = max_delay_ms;
}

std::uint64_t CameraServer::FramesExposed() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->exposed;
}

std::uint64_t CameraServer::FramesDropped() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->dropped;
}

std::uint64_t CameraServer::LinePulsesAccepted() const { return impl_->pulses_accepted; }

std::vector<FrameRecord> CameraServer::RecentFrames() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return {impl_->records.begin(), impl_->records.end()};
}

CameraServerStats CameraServer::Stats() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->stats;
}

}  // namespace irdist::sim
