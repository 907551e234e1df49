#include "sim/camera_server.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "base/check.h"
#include "sim/trajectory.h"
#include "tests/loopback_gvcp.h"
#include "tests/sim/camera_server_fixture.h"

// The virtual camera as a device (sim/camera_server_device.cc): start and stop, the registers'
// power-up values, the triggers (Line1 pulses and TriggerSoftware, a queue of 4), the fault knobs'
// checks. The GVCP capability register (bootstrap 0x0934) declares WRITEMEM in bit 30 and
// PACKETRESEND in bit 29 (GigE Vision numbers bit 0 as the most significant): 1 << 1 and 1 << 2.

namespace irdist::sim {
namespace {

using CameraServerDeviceTest = CameraFixture<10>;
using CameraServerDeviceRealTimeTest = CameraFixture<1>;

constexpr std::uint32_t kRegSensorHeight = 0x118, kRegSensorWidth = 0x11c;
constexpr std::uint32_t kRegDeviceTemperature = 0x8008;  // milli-degrees Celsius, signed
constexpr std::uint32_t kRegGvcpCapability = 0x934;

// Power-up: the full sensor, Line1 as trigger source, the temperature in milli-degrees, and the
// capability register declaring WRITEMEM and PACKETRESEND; resend off clears only its own bit.
TEST_F(CameraServerDeviceTest, RegistersHoldTheirPowerUpValues) {
  EXPECT_EQ(Read(kRegWidth), 1280u);
  EXPECT_EQ(Read(kRegHeight), 1024u);
  EXPECT_EQ(Read(kRegSensorWidth), 1280u);
  EXPECT_EQ(Read(kRegSensorHeight), 1024u);
  EXPECT_EQ(Read(kRegTriggerSource), 2u);
  EXPECT_EQ(Read(kRegDeviceTemperature), 40000u);
  const std::uint32_t capability = Read(kRegGvcpCapability);
  EXPECT_EQ(capability & 0x6u, 0x6u);
  server_->SetPacketResend(false);
  EXPECT_EQ(Read(kRegGvcpCapability), capability & ~0x4u);
  server_->SetPacketResend(true);
  EXPECT_EQ(Read(kRegGvcpCapability), capability);
}

// Stop frees UDP 3956 at once, twice is harmless, and the camera starts again.
TEST_F(CameraServerDeviceTest, StopFreesThePortAndTheCameraStartsAgain) {
  EXPECT_TRUE(server_->running());
  EXPECT_FALSE(irdist::testing::LoopbackGvcpPortFree());
  server_->Stop();
  EXPECT_FALSE(server_->running());
  EXPECT_TRUE(irdist::testing::LoopbackGvcpPortFree());
  server_->Stop();
  EXPECT_FALSE(server_->running());
  server_->Start();
  EXPECT_TRUE(server_->running());
  EXPECT_EQ(Read(kRegWidth), 1280u);
  server_->Start();  // already running: nothing changes
  EXPECT_TRUE(server_->running());
}

TEST(CameraServerDevice, NamesItselfAsAravisNamesAFakeCamera) {
  RigPhysics physics;
  physics.camera.serial = "IRDDEV07";
  World world(1.0);
  CameraServer server(world, physics);
  EXPECT_EQ(server.serial(), "IRDDEV07");
  EXPECT_EQ(server.device_id(), "Aravis-Fake-IRDDEV07");
  EXPECT_EQ(server.address(), "127.0.0.1");
  EXPECT_FALSE(server.running());
}

TEST(CameraServerDevice, FaultKnobsOutsideTheirRangesAreRefused) {
  RigPhysics physics;
  World world(1.0);
  CameraServer server(world, physics);
  EXPECT_THROW(server.SetDropFrameRate(1.5), Error);
  EXPECT_THROW(server.SetDropFrameRate(-0.1), Error);
  EXPECT_THROW(server.SetLostPacketRatio(1.01), Error);
  EXPECT_THROW(server.SetExposureWriteDelayMs(-1.0), Error);
  EXPECT_THROW(server.SetExposureWriteDelayMs(std::nan("")), Error);
  EXPECT_NO_THROW(server.SetDropFrameRate(1.0));
  EXPECT_NO_THROW(server.SetLostPacketRatio(0.0));
  EXPECT_NO_THROW(server.SetExposureWriteDelayMs(0.0));
}

// A Line1 pulse starts a frame only with TriggerMode On, TriggerSource Line1 and acquisition on;
// with TriggerSource Software the line is not listened to, with acquisition off it is ignored.
TEST_F(CameraServerDeviceTest, Line1PulsesTriggerOnlyWhenLine1IsTheArmedSource) {
  Configure(32, 8, kMono8, 1500);  // TriggerSource Software
  world_.FireTrigger();
  EXPECT_TRUE(Receive(stream_, 300).empty());
  EXPECT_EQ(server_->LinePulsesAccepted(), 0u);
  Write(kRegTriggerSource, 2);  // Line1
  world_.FireTrigger();
  EXPECT_FALSE(Receive(stream_, 2000).empty());
  EXPECT_EQ(server_->LinePulsesAccepted(), 1u);
  while (!Receive(stream_, 300).empty()) {
  }
  Write(kRegAcquisition, 0);
  world_.FireTrigger();
  EXPECT_TRUE(Receive(stream_, 300).empty());
  EXPECT_EQ(server_->LinePulsesAccepted(), 1u);
  EXPECT_EQ(server_->Stats().triggers_ignored, 1u);
  EXPECT_EQ(server_->FramesExposed(), 1u);
}

// Triggers arriving while a 100 ms frame is exposed wait in a queue of 4; the rest are ignored.
// 1 + 4 frames in all.
TEST_F(CameraServerDeviceRealTimeTest, TriggersDuringAFrameQueueUpToFour) {
  Configure(16, 4, kMono8, 1500, 100000);
  Write(kRegTriggerSoftware, 1);
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  for (int i = 0; i < 6; ++i) Write(kRegTriggerSoftware, 1);
  Read(kRegWidth);  // served after the last trigger was offered (one control thread)
  const CameraServerStats stats = server_->Stats();
  EXPECT_EQ(stats.triggers_queued, 4u);
  EXPECT_EQ(stats.triggers_ignored, 2u);
  Write(kRegExposureUs, 1000);  // the queued frames latch it when they start
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(2);
  while (server_->FramesExposed() < 5 && std::chrono::steady_clock::now() < until) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  EXPECT_EQ(server_->FramesExposed(), 5u);
  const std::vector<FrameRecord> frames = server_->RecentFrames();
  ASSERT_EQ(frames.size(), 5u);
  EXPECT_EQ(frames[0].exposure_us, 100000.0);
  EXPECT_EQ(frames[4].exposure_us, 1000.0);
}

}  // namespace
}  // namespace irdist::sim
