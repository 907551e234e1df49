#include "sim/camera_server.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "tests/loopback_gvcp.h"
#include "tests/sim/camera_server_fixture.h"

// The virtual camera's control channel (sim/camera_server_gvcp.cc) spoken to in raw GVCP packets.
// The expected bytes come from the GigE Vision specification: a command is the key 0x42, a flags
// byte, the 16-bit command, the 16-bit length of what follows and the 16-bit request id, all big
// endian; its acknowledge is the 16-bit status, the command + 1, the length and the same request
// id. Commands: DISCOVERY 0x0002, READREG 0x0080, WRITEREG 0x0082, READMEM 0x0084, WRITEMEM 0x0086.
// Status: SUCCESS 0x0000, NOT_IMPLEMENTED 0x8001, INVALID_PARAMETER 0x8002, ACCESS_DENIED 0x8006.
// Bootstrap registers: manufacturer name at 0x0048 (32 bytes), model name at 0x0068, serial
// number at 0x00d8 (16 bytes), heartbeat timeout at 0x0938, control channel privilege at 0x0a00.

namespace irdist::sim {
namespace {

constexpr char kSerial[] = "IRDGVCP01";
constexpr std::uint32_t kRegHeartbeatMs = 0x938;
constexpr std::uint32_t kRegPrivilege = 0xa00;

std::vector<std::uint8_t> Be32(std::uint32_t v) {
  return {static_cast<std::uint8_t>(v >> 24), static_cast<std::uint8_t>(v >> 16),
          static_cast<std::uint8_t>(v >> 8), static_cast<std::uint8_t>(v)};
}

// A GVCP application on its own UDP socket.
class GvcpClient {
 public:
  GvcpClient() {
    fd_ = ::socket(AF_INET, SOCK_DGRAM, 0);
    sockaddr_in local{};
    local.sin_family = AF_INET;
    local.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    EXPECT_EQ(::bind(fd_, reinterpret_cast<sockaddr*>(&local), sizeof(local)), 0);
  }
  ~GvcpClient() { ::close(fd_); }
  GvcpClient(const GvcpClient&) = delete;
  GvcpClient& operator=(const GvcpClient&) = delete;

  // Sends raw bytes to 127.0.0.1:3956; returns the acknowledge, or {} after `timeout_ms`.
  std::vector<std::uint8_t> SendRaw(const std::vector<std::uint8_t>& packet,
                                    int timeout_ms = 2000) {
    sockaddr_in camera{};
    camera.sin_family = AF_INET;
    camera.sin_port = htons(3956);
    camera.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    EXPECT_EQ(::sendto(fd_, packet.data(), packet.size(), 0,
                       reinterpret_cast<sockaddr*>(&camera), sizeof(camera)),
              static_cast<ssize_t>(packet.size()));
    pollfd wait{fd_, POLLIN, 0};
    if (::poll(&wait, 1, timeout_ms) != 1) return {};
    std::vector<std::uint8_t> ack(2048);
    const ssize_t got = ::recv(fd_, ack.data(), ack.size(), 0);
    ack.resize(got > 0 ? static_cast<std::size_t>(got) : 0);
    return ack;
  }
  std::vector<std::uint8_t> Command(std::uint16_t command, const std::vector<std::uint8_t>& data,
                                    std::uint16_t id) {
    std::vector<std::uint8_t> packet = {0x42, 0x01, static_cast<std::uint8_t>(command >> 8),
                                        static_cast<std::uint8_t>(command),
                                        static_cast<std::uint8_t>(data.size() >> 8),
                                        static_cast<std::uint8_t>(data.size()),
                                        static_cast<std::uint8_t>(id >> 8),
                                        static_cast<std::uint8_t>(id)};
    packet.insert(packet.end(), data.begin(), data.end());
    return SendRaw(packet);
  }
  std::uint32_t ReadRegister(std::uint32_t address) {
    const std::vector<std::uint8_t> ack = Command(0x0080, Be32(address), NextId());
    EXPECT_EQ(ack.size(), 12u);
    return ack.size() == 12 ? U32(ack, 8) : 0xdeadbeef;
  }
  // The acknowledge's status.
  std::uint16_t WriteRegister(std::uint32_t address, std::uint32_t value) {
    std::vector<std::uint8_t> data = Be32(address);
    const std::vector<std::uint8_t> v = Be32(value);
    data.insert(data.end(), v.begin(), v.end());
    const std::vector<std::uint8_t> ack = Command(0x0082, data, NextId());
    EXPECT_GE(ack.size(), 8u);
    return ack.size() >= 8 ? U16(ack, 0) : 0xffff;
  }
  std::uint16_t NextId() { return ++id_; }

 private:
  int fd_ = -1;
  std::uint16_t id_ = 0;
};

// The text of a NUL-padded bootstrap string field.
std::string Field(const std::vector<std::uint8_t>& bytes, std::size_t at, std::size_t size) {
  std::string text;
  for (std::size_t i = at; i < at + size && i < bytes.size() && bytes[i] != 0; ++i) {
    text.push_back(static_cast<char>(bytes[i]));
  }
  return text;
}

class CameraServerGvcpTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(irdist::testing::WaitForLoopbackGvcpPort(std::chrono::seconds(120)))
        << "127.0.0.1:3956 stayed busy: another fake camera is running";
    physics_.time_scale = 10.0;
    physics_.camera.serial = kSerial;
    server_ = std::make_unique<CameraServer>(world_, physics_);
    server_->Start();
  }

  RigPhysics physics_;
  World world_{10.0};
  std::unique_ptr<CameraServer> server_;
  GvcpClient client_;
};

// READREG of two registers: one acknowledge with both values, in the order asked.
TEST_F(CameraServerGvcpTest, ReadRegisterAcknowledgesWithStatusAckCodeLengthAndRequestId) {
  std::vector<std::uint8_t> data = Be32(kRegWidth);
  const std::vector<std::uint8_t> second = Be32(kRegWidth + 4);  // Height
  data.insert(data.end(), second.begin(), second.end());
  const std::vector<std::uint8_t> ack = client_.Command(0x0080, data, 0x1234);
  ASSERT_EQ(ack.size(), 8u + 8u);
  EXPECT_EQ(U16(ack, 0), 0x0000);  // SUCCESS
  EXPECT_EQ(U16(ack, 2), 0x0081);  // READREG_ACK
  EXPECT_EQ(U16(ack, 4), 8);       // two registers of 4 bytes
  EXPECT_EQ(U16(ack, 6), 0x1234);
  EXPECT_EQ(U32(ack, 8), static_cast<std::uint32_t>(physics_.sensor.width_px));
  EXPECT_EQ(U32(ack, 12), static_cast<std::uint32_t>(physics_.sensor.height_px));
}

// WRITEREG of two registers: the acknowledge's index is the number of entries written.
TEST_F(CameraServerGvcpTest, WriteRegisterAcknowledgesTheNumberOfEntriesWritten) {
  std::vector<std::uint8_t> data;
  for (const std::uint32_t word : {kRegExposureUs, 12345u, kRegHeartbeatMs, 1500u}) {
    const std::vector<std::uint8_t> b = Be32(word);
    data.insert(data.end(), b.begin(), b.end());
  }
  const std::vector<std::uint8_t> ack = client_.Command(0x0082, data, 77);
  ASSERT_EQ(ack.size(), 12u);
  EXPECT_EQ(U16(ack, 0), 0x0000);
  EXPECT_EQ(U16(ack, 2), 0x0083);  // WRITEREG_ACK
  EXPECT_EQ(U16(ack, 4), 4);
  EXPECT_EQ(U16(ack, 6), 77);
  EXPECT_EQ(U16(ack, 10), 2);      // index: both entries written
  EXPECT_EQ(client_.ReadRegister(kRegExposureUs), 12345u);
  EXPECT_EQ(client_.ReadRegister(kRegHeartbeatMs), 1500u);
}

// READMEM of the bootstrap's identity: the acknowledge echoes the address, then the bytes.
TEST_F(CameraServerGvcpTest, ReadMemoryReturnsTheBootstrapIdentityAfterTheAddress) {
  std::vector<std::uint8_t> data = Be32(0x0048);
  for (const std::uint8_t b : {0x00, 0x00, 0x00, 0xb0}) data.push_back(b);  // reserved, count 176
  const std::vector<std::uint8_t> ack = client_.Command(0x0084, data, 9);
  ASSERT_EQ(ack.size(), 8u + 4u + 0xb0u);
  EXPECT_EQ(U16(ack, 0), 0x0000);
  EXPECT_EQ(U16(ack, 2), 0x0085);  // READMEM_ACK
  EXPECT_EQ(U16(ack, 4), 4 + 0xb0);
  EXPECT_EQ(U32(ack, 8), 0x0048u);
  const std::size_t base = 12 - 0x48;  // byte of bootstrap address a is ack[base + a]
  EXPECT_EQ(Field(ack, base + 0x48, 32), "Aravis");
  EXPECT_EQ(Field(ack, base + 0x68, 32), "Fake");
  EXPECT_EQ(Field(ack, base + 0xd8, 16), kSerial);
}

// READMEM's count must be a multiple of 4 and fit one packet (536 bytes of data).
TEST_F(CameraServerGvcpTest, ReadMemoryOfABadCountIsAnInvalidParameter) {
  for (const std::uint16_t count : {6, 540}) {
    std::vector<std::uint8_t> data = Be32(0x0048);
    for (const std::uint8_t b : {std::uint8_t{0}, std::uint8_t{0},
                                 static_cast<std::uint8_t>(count >> 8),
                                 static_cast<std::uint8_t>(count)}) {
      data.push_back(b);
    }
    const std::vector<std::uint8_t> ack = client_.Command(0x0084, data, 5);
    ASSERT_EQ(ack.size(), 8u) << count;
    EXPECT_EQ(U16(ack, 0), 0x8002) << count;  // INVALID_PARAMETER
    EXPECT_EQ(U16(ack, 2), 0x0085);
  }
  std::vector<std::uint8_t> data = Be32(0x0048);
  for (const std::uint8_t b : {0x00, 0x00, 0x02, 0x18}) data.push_back(b);  // 536: the largest
  const std::vector<std::uint8_t> ack = client_.Command(0x0084, data, 6);
  ASSERT_EQ(ack.size(), 8u + 4u + 536u);
  EXPECT_EQ(U16(ack, 0), 0x0000);
}

// A command the camera does not implement is answered NOT_IMPLEMENTED; a packet that is not GVCP
// (no 0x42 key) gets no answer; one whose length field exceeds the packet is INVALID_PARAMETER.
TEST_F(CameraServerGvcpTest, UnknownCommandsForeignPacketsAndShortPacketsAreAnsweredAsTheSpecSays) {
  const std::vector<std::uint8_t> action = client_.Command(0x0100, {}, 3);  // ACTION_CMD
  ASSERT_EQ(action.size(), 8u);
  EXPECT_EQ(U16(action, 0), 0x8001);  // NOT_IMPLEMENTED
  EXPECT_EQ(U16(action, 2), 0x0101);
  EXPECT_EQ(U16(action, 6), 3);

  EXPECT_TRUE(client_.SendRaw({0x43, 0x01, 0x00, 0x80, 0x00, 0x04, 0x00, 0x04, 0, 0, 1, 0}, 300)
                  .empty());

  const std::vector<std::uint8_t> short_read =
      client_.SendRaw({0x42, 0x01, 0x00, 0x80, 0x00, 0x08, 0x00, 0x05, 0, 0, 1, 0});
  ASSERT_EQ(short_read.size(), 8u);
  EXPECT_EQ(U16(short_read, 0), 0x8002);
  EXPECT_EQ(U16(short_read, 2), 0x0081);
  EXPECT_EQ(U16(short_read, 6), 5);
}

// Unicast DISCOVERY_CMD: DISCOVERY_ACK (0x0003) of 0xf8 bytes, the bootstrap's first bytes, with
// the manufacturer, model and serial at their bootstrap offsets.
TEST_F(CameraServerGvcpTest, DiscoveryIsAcknowledgedWithTheDevicesIdentity) {
  const std::vector<std::uint8_t> ack = client_.Command(0x0002, {}, 0x0101);
  ASSERT_EQ(ack.size(), 8u + 0xf8u);
  EXPECT_EQ(U16(ack, 0), 0x0000);
  EXPECT_EQ(U16(ack, 2), 0x0003);
  EXPECT_EQ(U16(ack, 4), 0xf8);
  EXPECT_EQ(U16(ack, 6), 0x0101);
  EXPECT_EQ(Field(ack, 8 + 0x48, 32), "Aravis");
  EXPECT_EQ(Field(ack, 8 + 0x68, 32), "Fake");
  EXPECT_EQ(Field(ack, 8 + 0xd8, 16), kSerial);
}

// With control privilege taken by one application, another's writes are ACCESS_DENIED (and
// change nothing) while its reads are served; once released, the other may write.
TEST_F(CameraServerGvcpTest, OnlyTheControllerMayWriteWhileItHoldsThePrivilege) {
  ASSERT_EQ(client_.WriteRegister(kRegExposureUs, 10000), 0x0000);
  ASSERT_EQ(client_.WriteRegister(kRegPrivilege, 2), 0x0000);  // control access
  GvcpClient other;
  EXPECT_EQ(other.WriteRegister(kRegExposureUs, 20000), 0x8006);  // ACCESS_DENIED
  std::vector<std::uint8_t> data = Be32(kRegExposureUs);
  const std::vector<std::uint8_t> v = Be32(30000);
  data.insert(data.end(), v.begin(), v.end());
  const std::vector<std::uint8_t> memory_ack = other.Command(0x0086, data, 1);  // WRITEMEM
  ASSERT_GE(memory_ack.size(), 8u);
  EXPECT_EQ(U16(memory_ack, 0), 0x8006);
  EXPECT_EQ(U16(memory_ack, 2), 0x0087);
  EXPECT_EQ(other.ReadRegister(kRegExposureUs), 10000u);
  EXPECT_EQ(client_.ReadRegister(kRegPrivilege), 2u);

  ASSERT_EQ(client_.WriteRegister(kRegPrivilege, 0), 0x0000);  // released
  EXPECT_EQ(other.WriteRegister(kRegExposureUs, 20000), 0x0000);
  EXPECT_EQ(client_.ReadRegister(kRegExposureUs), 20000u);
}

// With the write-delay fault, an ExposureTime write is acknowledged at once but read back old
// until it lands, at most the delay (100 ms) later. The delay is uniform on [0, 100] ms: a read
// 1 ms after the write finds the old value about 99 times in 100, so at least once in 5.
TEST_F(CameraServerGvcpTest, DelayedExposureWritesAreAcknowledgedAtOnceAndLandLater) {
  ASSERT_EQ(client_.WriteRegister(kRegExposureUs, 10000), 0x0000);
  server_->SetExposureWriteDelayMs(100.0);
  int old_seen = 0;
  std::uint32_t previous = 10000;
  for (std::uint32_t exposure_us : {21000u, 22000u, 23000u, 24000u, 25000u}) {
    ASSERT_EQ(client_.WriteRegister(kRegExposureUs, exposure_us), 0x0000);
    if (client_.ReadRegister(kRegExposureUs) == previous) ++old_seen;
    std::this_thread::sleep_for(std::chrono::milliseconds(150));
    EXPECT_EQ(client_.ReadRegister(kRegExposureUs), exposure_us) << "not applied within 100 ms";
    previous = exposure_us;
  }
  EXPECT_GE(old_seen, 1) << "every write took effect at once";
  EXPECT_EQ(server_->Stats().exposure_writes_delayed, 5u);
  // 16 requests; the last is counted just after its acknowledge left, maybe not yet.
  EXPECT_GE(server_->Stats().control_requests, 15u);
}

}  // namespace
}  // namespace irdist::sim
