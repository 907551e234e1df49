// The virtual camera's stream channel (sim/camera_server_impl.h): a frame as GVSP packets (leader,
// payload with the chunks, trailer), sent to the host with the lost-packet fault, and sent again
// on a PACKETRESEND request.
#include <arpa/inet.h>
#include <sys/socket.h>

#include <algorithm>
#include <cstring>
#include <mutex>
#include <random>

#include "sim/camera_server_impl.h"

namespace irdist::sim {
namespace {

// GVSP (stream protocol) packet formats and payload types.
constexpr std::uint8_t kGvspLeader = 1;
constexpr std::uint8_t kGvspTrailer = 2;
constexpr std::uint8_t kGvspPayload = 3;
constexpr std::uint16_t kPayloadImage = 0x0001;
constexpr std::uint16_t kPayloadImageWithChunks = 0x4001;
constexpr std::size_t kGvspOverhead = 20 + 8 + 8;  // IP + UDP + GVSP headers
constexpr std::uint32_t kImageChunkId = 0x00000001;
constexpr std::uint32_t kExposureChunkId = 0x00001001;  // sim/virtual_camera.xml's ChunkID

}  // namespace

bool CameraServer::Impl::Lose(std::mt19937_64& rng) {
  return std::uniform_real_distribution<double>(0.0, 1.0)(rng) < lost_ratio.load();
}

void CameraServer::Impl::SendPacket(const std::vector<std::uint8_t>& packet,
                                    const sockaddr_in& to) {
  if (ntohl(to.sin_addr.s_addr) >> 24 != 127 || to.sin_port == 0) return;  // loopback only
  (void)::sendto(stream_fd, packet.data(), packet.size(), 0,
                 reinterpret_cast<const sockaddr*>(&to), sizeof(to));
}

void CameraServer::Impl::Resend(std::uint32_t block, std::uint32_t first, std::uint32_t last) {
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

std::vector<std::uint8_t> CameraServer::Impl::GvspHeader(std::uint16_t block_id,
                                                         std::uint8_t format,
                                                         std::uint32_t packet_id) {
  std::vector<std::uint8_t> packet;
  PutU16(packet, 0);
  PutU16(packet, block_id);
  PutU32(packet, (static_cast<std::uint32_t>(format) << 24) | (packet_id & 0xffffff));
  return packet;
}

std::vector<std::uint8_t> CameraServer::Impl::Leader(std::uint16_t block_id, const FrameSetup& s,
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

SentFrame CameraServer::Impl::Packetize(std::uint16_t block_id, const FrameSetup& s,
                                        const std::vector<std::uint8_t>& payload,
                                        std::uint64_t timestamp_ns) {
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

void CameraServer::Impl::AppendChunks(const FrameSetup& s, std::vector<std::uint8_t>& payload) {
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

void CameraServer::Impl::Transmit(const SentFrame& frame, const sockaddr_in& to) {
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

}  // namespace irdist::sim
