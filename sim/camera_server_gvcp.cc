// The virtual camera's control channel (sim/camera_server_impl.h): GVCP commands on UDP 3956
// (register and memory reads and writes, discovery, packet resend requests), the controller's
// privilege and heartbeat, delayed ExposureTime writes.
#include <arpa/inet.h>
#include <poll.h>
#include <sys/socket.h>

#include <cmath>
#include <mutex>
#include <random>

#include "sim/camera_server_impl.h"

namespace irdist::sim {
namespace {

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

}  // namespace

bool CameraServer::Impl::SameAddress(const sockaddr_in& a, const sockaddr_in& b) {
  return a.sin_addr.s_addr == b.sin_addr.s_addr && a.sin_port == b.sin_port;
}

bool CameraServer::Impl::MayWrite(const sockaddr_in& from) const {
  return !have_controller || SameAddress(from, controller);
}

void CameraServer::Impl::TrackController(const sockaddr_in& from) {
  const bool privileged = ReadLocked(kRegControlPrivilege) != 0;
  if (!have_controller && privileged) {
    have_controller = true;
    controller = from;
    controller_seen = SteadyClock::now();
    WriteLocked(kRegPrimaryAppPort, ntohs(from.sin_port));
    WriteLocked(kRegPrimaryAppAddress, ntohl(from.sin_addr.s_addr));
  } else if (have_controller && !privileged) {
    ReleaseControllerLocked();
  }
}

void CameraServer::Impl::ReleaseControllerLocked() {
  have_controller = false;
  WriteLocked(kRegControlPrivilege, 0);
  WriteLocked(kRegPrimaryAppPort, 0);
  WriteLocked(kRegPrimaryAppAddress, 0);
  WriteLocked(kRegAcquisition, 0);
}

void CameraServer::Impl::ExpireController() {
  std::lock_guard<std::mutex> lock(reg_mutex);
  if (!have_controller) return;
  const auto timeout = std::chrono::milliseconds(ReadLocked(kRegHeartbeatMs));
  if (SteadyClock::now() - controller_seen <= timeout) return;
  ReleaseControllerLocked();
  std::lock_guard<std::mutex> count_lock(mutex);
  ++stats.controllers_expired;
}

void CameraServer::Impl::WriteRegisterFromNetwork(guint32 address, guint32 value) {
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

void CameraServer::Impl::ApplyDueWrites() {
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

std::vector<std::uint8_t> CameraServer::Impl::AckHeader(std::uint16_t status, std::uint16_t command,
                                                        std::uint16_t length,
                                                        std::uint16_t request_id) const {
  std::vector<std::uint8_t> ack;
  PutU16(ack, status);
  PutU16(ack, static_cast<std::uint16_t>(command + 1));
  PutU16(ack, length);
  PutU16(ack, request_id);
  return ack;
}

std::vector<std::uint8_t> CameraServer::Impl::Serve(const std::uint8_t* packet, std::size_t size,
                                                    const sockaddr_in& from,
                                                    bool* fire_software_trigger) {
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

std::vector<std::uint8_t> CameraServer::Impl::ReadRegistersAck(std::uint16_t command,
                                                               std::uint16_t request_id,
                                                               const std::uint8_t* data,
                                                               std::size_t length) {
  const std::size_t count = length / 4;
  std::vector<std::uint8_t> ack =
      AckHeader(kStatusOk, command, static_cast<std::uint16_t>(count * 4), request_id);
  for (std::size_t i = 0; i < count; ++i) PutU32(ack, ReadLocked(GetU32(data + 4 * i)));
  return ack;
}

std::vector<std::uint8_t> CameraServer::Impl::WriteRegistersAck(
    std::uint16_t command, std::uint16_t request_id, const std::uint8_t* data, std::size_t length,
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

std::vector<std::uint8_t> CameraServer::Impl::ReadMemoryAck(std::uint16_t command,
                                                            std::uint16_t request_id,
                                                            guint32 address, std::size_t count,
                                                            bool with_address) {
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

std::vector<std::uint8_t> CameraServer::Impl::WriteMemoryAck(std::uint16_t command,
                                                             std::uint16_t request_id,
                                                             const std::uint8_t* data,
                                                             std::size_t length,
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

void CameraServer::Impl::ControlLoop() {
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

void CameraServer::Impl::ServeOne(std::vector<std::uint8_t>& packet) {
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

void CameraServer::Impl::ServeDiscovery(std::vector<std::uint8_t>& packet) {
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

}  // namespace irdist::sim
