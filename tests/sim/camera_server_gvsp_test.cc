#include "sim/camera_server.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "tests/loopback_gvcp.h"
#include "tests/sim/camera_server_fixture.h"

// The virtual camera's stream channel (sim/camera_server_gvsp.cc) received as raw GVSP packets.
// The expected layout comes from the GigE Vision specification (standard, not extended, ids):
// every packet starts with the 16-bit status, the 16-bit block id, then one 32-bit word holding
// the packet format in its top byte (LEADER 1, TRAILER 2, PAYLOAD 3) and the 24-bit packet id.
// The image leader follows with 16 reserved bits, the 16-bit payload type (image 0x0001, image
// with chunks 0x4001), the 64-bit timestamp, pixel format, size x, size y, offset x, offset y
// (32 bits each) and padding x, y (16 bits each); the image trailer with 16 reserved bits, the
// payload type and size y. The stream's destination is the bootstrap's SCP0 (port, 0x0d00),
// SCPS0 (packet size, 0x0d04) and SCDA0 (address, 0x0d18). A chunk ends with its 32-bit id and
// 32-bit length, so the chunk data is read from the end of the payload.

namespace irdist::sim {
namespace {

class CameraServerGvspTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(irdist::testing::WaitForLoopbackGvcpPort(std::chrono::seconds(120)))
        << "127.0.0.1:3956 stayed busy: another fake camera is running";
    physics_.time_scale = 10.0;
    server_ = std::make_unique<CameraServer>(world_, physics_);
    server_->Start();
    control_ = LoopbackSocket(nullptr);
    stream_ = LoopbackSocket(&stream_port_);
    world_.SetPose(2000, 0, 0, false);
    world_.SetCurrent(500);
  }
  void TearDown() override {
    server_.reset();
    ::close(control_);
    ::close(stream_);
  }

  void Write(std::uint32_t address, std::uint32_t value) {
    const std::uint8_t packet[] = {
        0x42, 0x01, 0x00, 0x82, 0x00, 0x08, 0x00, ++id_,
        static_cast<std::uint8_t>(address >> 24), static_cast<std::uint8_t>(address >> 16),
        static_cast<std::uint8_t>(address >> 8), static_cast<std::uint8_t>(address),
        static_cast<std::uint8_t>(value >> 24), static_cast<std::uint8_t>(value >> 16),
        static_cast<std::uint8_t>(value >> 8), static_cast<std::uint8_t>(value)};
    SendControl(packet, sizeof(packet));
    const std::vector<std::uint8_t> ack = Receive(control_, 2000);
    ASSERT_EQ(ack.size(), 12u) << "no WRITEREG_ACK for 0x" << std::hex << address;
    ASSERT_EQ(U16(ack, 0), 0) << "write of 0x" << std::hex << address << " refused";
  }
  void SendControl(const std::uint8_t* packet, std::size_t size) {
    sockaddr_in camera{};
    camera.sin_family = AF_INET;
    camera.sin_port = htons(3956);
    camera.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ASSERT_EQ(::sendto(control_, packet, size, 0, reinterpret_cast<sockaddr*>(&camera),
                       sizeof(camera)),
              static_cast<ssize_t>(size));
  }

  // Region, format and stream destination; software-triggered frames of 1 ms.
  void Configure(int width, int height, std::uint32_t format, std::uint32_t packet_size) {
    Write(kRegWidth, static_cast<std::uint32_t>(width));
    Write(kRegHeight, static_cast<std::uint32_t>(height));
    Write(kRegOffsetX, 600);
    Write(kRegOffsetY, 480);
    Write(kRegPixelFormat, format);
    Write(kRegExposureUs, 1000);
    Write(kRegStreamAddress, 0x7f000001);
    Write(kRegStreamPort, stream_port_);
    Write(kRegPacketSize, packet_size);
    Write(kRegTriggerMode, 1);
    Write(kRegTriggerSource, 1);
    Write(kRegAcquisition, 1);
  }
  // One triggered frame's packets, up to the trailer (or what came before a silence).
  std::vector<std::vector<std::uint8_t>> Frame(int silence_ms = 2000) {
    Write(kRegTriggerSoftware, 1);
    std::vector<std::vector<std::uint8_t>> packets;
    while (true) {
      std::vector<std::uint8_t> packet = Receive(stream_, silence_ms);
      if (packet.empty()) break;
      packets.push_back(packet);
      if (packet.size() >= 8 && packet[4] == 2) break;  // trailer
    }
    return packets;
  }

  RigPhysics physics_;
  World world_{10.0};
  std::unique_ptr<CameraServer> server_;
  int control_ = -1, stream_ = -1;
  std::uint16_t stream_port_ = 0;
  std::uint8_t id_ = 0;
};

// 100 x 20 Mono8 = 2000 bytes in packets of 576 bytes (20 IP + 8 UDP + 8 GVSP header = 540 of
// data each): a leader (id 0), 4 payload packets (ids 1-4, 540 + 540 + 540 + 380 bytes) and a
// trailer (id 5), all of one block.
TEST_F(CameraServerGvspTest, AFrameIsALeaderPayloadPacketsWithinThePacketSizeAndATrailer) {
  Configure(100, 20, kMono8, 576);
  const std::vector<std::vector<std::uint8_t>> packets = Frame();
  ASSERT_EQ(packets.size(), 6u);
  const std::uint16_t block = U16(packets[0], 2);
  EXPECT_NE(block, 0) << "block id 0 is reserved";
  const std::size_t sizes[] = {540, 540, 540, 380};
  for (std::size_t i = 0; i < packets.size(); ++i) {
    EXPECT_EQ(U16(packets[i], 0), 0) << "status of packet " << i;
    EXPECT_EQ(U16(packets[i], 2), block) << "block of packet " << i;
    const std::uint32_t word = U32(packets[i], 4);
    EXPECT_EQ(word & 0xffffff, i) << "packet id";
    const std::uint32_t format = word >> 24;
    EXPECT_EQ(format, i == 0 ? 1u : i + 1 == packets.size() ? 2u : 3u) << "format of " << i;
    if (format == 3) {
      EXPECT_EQ(packets[i].size(), 8 + sizes[i - 1]) << "payload packet " << i;
      EXPECT_LE(packets[i].size() + 28, 576u);
    }
  }
  EXPECT_EQ(packets.back().size(), 8u + 8u);
  EXPECT_EQ(U16(packets.back(), 10), 0x0001);  // image
  EXPECT_EQ(U32(packets.back(), 12), 20u);     // size y
}

// The leader: image payload, the world's timestamp of the exposure's start, Mono16, the region.
TEST_F(CameraServerGvspTest, TheLeaderCarriesTimestampPixelFormatAndRegion) {
  Configure(64, 16, kMono16, 1500);
  const std::vector<std::vector<std::uint8_t>> packets = Frame();
  ASSERT_GE(packets.size(), 3u);
  const std::vector<std::uint8_t>& leader = packets[0];
  ASSERT_EQ(leader.size(), 8u + 36u);
  EXPECT_EQ(U16(leader, 10), 0x0001);
  const std::uint64_t timestamp_ns = (static_cast<std::uint64_t>(U32(leader, 12)) << 32) |
                                     U32(leader, 16);
  EXPECT_EQ(U32(leader, 20), kMono16);
  EXPECT_EQ(U32(leader, 24), 64u);
  EXPECT_EQ(U32(leader, 28), 16u);
  EXPECT_EQ(U32(leader, 32), 600u);
  EXPECT_EQ(U32(leader, 36), 480u);
  EXPECT_EQ(U32(leader, 40), 0u);  // no padding
  const std::vector<FrameRecord> frames = server_->RecentFrames();
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_EQ(timestamp_ns, frames[0].timestamp_ns);
  EXPECT_GT(timestamp_ns, 0u);
  EXPECT_EQ(U16(leader, 2), frames[0].block_id);
  // Mono16: 2 bytes a pixel, all of them in the payload packets.
  std::size_t bytes = 0;
  for (std::size_t i = 1; i + 1 < packets.size(); ++i) bytes += packets[i].size() - 8;
  EXPECT_EQ(bytes, 64u * 16u * 2u);
}

// With ChunkModeActive and ChunkEnable[ExposureTime], the payload type is 0x4001 and the image
// is followed by its chunk tag (id 1, length = image bytes), the exposure as an IEEE double and
// its tag (id 0x1001, length 8), read from the end.
TEST_F(CameraServerGvspTest, ChunksFollowTheImageWithTheExposureAsADouble) {
  Write(kRegChunkModeActive, 1);
  Write(kRegChunkEnableExposure, 1);
  Configure(40, 10, kMono8, 1500);
  const std::vector<std::vector<std::uint8_t>> packets = Frame();
  ASSERT_GE(packets.size(), 3u);
  EXPECT_EQ(U16(packets.front(), 10), 0x4001);
  EXPECT_EQ(U16(packets.back(), 10), 0x4001);
  std::vector<std::uint8_t> payload;
  for (std::size_t i = 1; i + 1 < packets.size(); ++i) {
    payload.insert(payload.end(), packets[i].begin() + 8, packets[i].end());
  }
  ASSERT_EQ(payload.size(), 400u + 8u + 8u + 8u);
  const std::size_t end = payload.size();
  EXPECT_EQ(U32(payload, end - 8), 0x1001u);
  EXPECT_EQ(U32(payload, end - 4), 8u);
  const std::uint64_t bits =
      (static_cast<std::uint64_t>(U32(payload, end - 16)) << 32) | U32(payload, end - 12);
  double exposure_us = 0.0;
  std::memcpy(&exposure_us, &bits, sizeof(exposure_us));
  EXPECT_EQ(exposure_us, 1000.0);
  EXPECT_EQ(U32(payload, 400), 1u);    // the image chunk's id
  EXPECT_EQ(U32(payload, 404), 400u);  // and its length
}

// PACKETRESEND (GVCP 0x0040: block id, first and last packet id) sends those packets again,
// byte for byte, and no acknowledge.
TEST_F(CameraServerGvspTest, PacketResendSendsTheAskedPacketsAgainByteForByte) {
  Configure(100, 20, kMono8, 576);
  const std::vector<std::vector<std::uint8_t>> packets = Frame();
  ASSERT_EQ(packets.size(), 6u);
  const std::uint16_t block = U16(packets[0], 2);
  const std::uint8_t resend[] = {0x42, 0x00, 0x00, 0x40, 0x00, 0x0c, 0x00, 0x99,
                                 0x00, 0x00, static_cast<std::uint8_t>(block >> 8),
                                 static_cast<std::uint8_t>(block),
                                 0x00, 0x00, 0x00, 0x02, 0x00, 0x00, 0x00, 0x03};
  SendControl(resend, sizeof(resend));
  EXPECT_EQ(Receive(stream_, 2000), packets[2]);
  EXPECT_EQ(Receive(stream_, 2000), packets[3]);
  EXPECT_TRUE(Receive(stream_, 200).empty()) << "more than packets 2-3 resent";
  EXPECT_TRUE(Receive(control_, 100).empty()) << "PACKETRESEND was acknowledged";
  const CameraServerStats stats = server_->Stats();
  EXPECT_EQ(stats.resend_requests, 1u);
  EXPECT_EQ(stats.packets_resent, 2u);
}

// With every packet lost, nothing arrives and each packet is counted lost.
TEST_F(CameraServerGvspTest, LostPacketsAreNotSentAndAreCounted) {
  server_->SetLostPacketRatio(1.0);
  Configure(100, 20, kMono8, 576);
  EXPECT_TRUE(Frame(500).empty());
  EXPECT_EQ(server_->Stats().packets_lost, 6u);
  EXPECT_EQ(server_->FramesExposed(), 1u);
}

}  // namespace
}  // namespace irdist::sim
