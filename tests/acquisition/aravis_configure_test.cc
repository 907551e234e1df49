// AravisCamera's Camera interface (acquisition/aravis_configure.cc): open by address with the
// serial checked, control taken before anything is written (a holder named from the GigE Vision
// 2.0 bootstrap's primary application registers, 0x0a10 port and 0x0a14 address), acquisition
// left running by a previous client stopped, the features recorded, the identity's one line, and
// what is said when the camera is left. On Aravis's fake camera (arv-fake-gv-camera-0.8), and on
// the virtual rig's camera (sim/camera_server.h) where a raw GVCP client plays another
// application: control privilege (0x0a00) and AcquisitionStart (0x0124, sim/virtual_camera.xml).
#include "acquisition/aravis_camera.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <string>
#include <thread>

#include "sim/camera_server.h"
#include "tests/acquisition/fake_camera_process.h"
#include "tests/loopback_gvcp.h"

namespace irdist {
namespace {

constexpr char kSerial[] = "IRDCFG01";

CameraSettings Settings() {
  CameraSettings settings;
  settings.pixel_format = "Mono8";
  settings.trigger_source = "Software";
  settings.width = 256;
  settings.height = 128;
  settings.exposure_us = 2000.0;
  return settings;
}

class AravisConfigureTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { fake_ = new testing::FakeCameraProcess(kSerial); }
  static void TearDownTestSuite() {
    delete fake_;
    fake_ = nullptr;
  }
  static testing::FakeCameraProcess* fake_;
};
testing::FakeCameraProcess* AravisConfigureTest::fake_ = nullptr;

// A camera answering with another serial than the rig's is another device: refused naming both.
TEST_F(AravisConfigureTest, ACameraWithAnotherSerialIsRefusedNamingBoth) {
  try {
    AravisCamera::Open("127.0.0.1", "IRDOTHER");
    FAIL() << "opened a camera with another serial";
  } catch (const CameraError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("has serial '" + std::string(kSerial) + "', expected 'IRDOTHER'"),
              std::string::npos)
        << what;
  }
  const auto camera = AravisCamera::Open("127.0.0.1");  // no serial expected: any
  EXPECT_EQ(camera->Identity().serial, kSerial);
  EXPECT_EQ(camera->Identity().BriefReport().rfind("Aravis Fake serial " + std::string(kSerial) +
                                                       " firmware ",
                                                   0),
            0u)
      << camera->Identity().BriefReport();
  EXPECT_NE(camera->Identity().BriefReport().find(" at 127.0.0.1"), std::string::npos);
}

// What recording.yaml records: the identity and settings as the camera reads them, and irdist's
// own notes (frame trigger, packet size, exposure check and bounds, sensor, pixel pipeline). The
// fake camera's serial number is its DeviceID.
TEST_F(AravisConfigureTest, ReadBackRecordsTheCamerasFeaturesAndIrdistsNotes) {
  auto camera = AravisCamera::Open("127.0.0.1", kSerial);
  EXPECT_EQ(camera->ReadBackFeatures().count("irdist.FrameTrigger"), 0u) << "before Configure";
  CameraSettings settings = Settings();
  settings.packet_size = 1400;
  camera->Configure(settings);
  const auto features = camera->ReadBackFeatures();
  EXPECT_EQ(features.at("DeviceVendorName"), "Aravis");
  EXPECT_EQ(features.at("DeviceID"), kSerial);
  EXPECT_EQ(features.at("PixelFormat"), "Mono8");
  EXPECT_EQ(features.at("Width"), "256");
  EXPECT_EQ(features.at("TriggerMode"), "On");
  EXPECT_EQ(features.at("irdist.FrameTrigger"), "FrameStart");
  EXPECT_EQ(features.at("irdist.PacketSize"), "1400");
  EXPECT_EQ(features.at("irdist.ExposureCheck"), "auto");
  // The fake camera offers Bayer formats besides Mono8: a colour sensor whose Mono it interpolates.
  EXPECT_EQ(features.at("irdist.Sensor").rfind("colour (Bayer pixel formats BayerBG8", 0), 0u)
      << features.at("irdist.Sensor");
  EXPECT_EQ(features.at("irdist.PixelPipeline"), "neutral");
  EXPECT_EQ(features.at("irdist.ExposureChunks"), "false");
  // arv-tool-0.8 reads ExposureTimeAbs min 10, max 1e+07 on the fake camera.
  EXPECT_EQ(features.at("irdist.ExposureBounds"), "[10, 1e+07] us (ExposureTimeAbs)");
}

// SetExposureUs writes, reads back and returns what the camera holds; a non-positive exposure is
// a programming error, refused before anything is sent.
TEST_F(AravisConfigureTest, TheExposureIsWrittenAndReadBack) {
  auto camera = AravisCamera::Open("127.0.0.1", kSerial);
  camera->Configure(Settings());
  EXPECT_DOUBLE_EQ(camera->ExposureUs(), 2000.0);
  EXPECT_NEAR(camera->SetExposureUs(7500.0), 7500.0, 1.0);
  camera->WriteExposureUs(3300.0);
  EXPECT_NEAR(camera->ExposureUs(), 3300.0, 1.0);
  EXPECT_THROW(camera->SetExposureUs(0.0), Error);
  EXPECT_THROW(camera->WriteExposureUs(-5.0), Error);
  EXPECT_NEAR(camera->ExposureUs(), 3300.0, 1.0);
}

// Leaving the camera: never configured, nothing to say; configured, either put back or left as
// set, saying which (the rig file's camera.restore_after).
TEST_F(AravisConfigureTest, LeavingTheCameraSaysWhetherItWasPutBack) {
  auto camera = AravisCamera::Open("127.0.0.1", kSerial);
  EXPECT_EQ(camera->LeaveAsFound(true), "");
  camera->Configure(Settings());
  camera->StartStream();
  const std::string left = camera->LeaveAsFound(false);
  EXPECT_FALSE(camera->streaming());
  EXPECT_NE(left.find("camera.restore_after: false"), std::string::npos) << left;
  EXPECT_EQ(camera->LeaveAsFound(true), "The camera was put back as it was found.");
}

// A raw GVCP application on its own UDP socket, to the camera on 127.0.0.1:3956.
class RawApplication {
 public:
  RawApplication() {
    fd_ = ::socket(AF_INET, SOCK_DGRAM, 0);
    sockaddr_in local{};
    local.sin_family = AF_INET;
    local.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    EXPECT_EQ(::bind(fd_, reinterpret_cast<sockaddr*>(&local), sizeof(local)), 0);
    socklen_t size = sizeof(local);
    ::getsockname(fd_, reinterpret_cast<sockaddr*>(&local), &size);
    port_ = ntohs(local.sin_port);
  }
  ~RawApplication() { ::close(fd_); }
  RawApplication(const RawApplication&) = delete;
  RawApplication& operator=(const RawApplication&) = delete;
  std::uint16_t port() const { return port_; }
  // WRITEREG; whether the camera acknowledged it with status 0.
  bool Write(std::uint32_t address, std::uint32_t value) {
    const std::uint8_t packet[] = {
        0x42, 0x01, 0x00, 0x82, 0x00, 0x08, 0x00, ++id_,
        static_cast<std::uint8_t>(address >> 24), static_cast<std::uint8_t>(address >> 16),
        static_cast<std::uint8_t>(address >> 8), static_cast<std::uint8_t>(address),
        static_cast<std::uint8_t>(value >> 24), static_cast<std::uint8_t>(value >> 16),
        static_cast<std::uint8_t>(value >> 8), static_cast<std::uint8_t>(value)};
    sockaddr_in camera{};
    camera.sin_family = AF_INET;
    camera.sin_port = htons(3956);
    camera.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ::sendto(fd_, packet, sizeof(packet), 0, reinterpret_cast<sockaddr*>(&camera), sizeof(camera));
    std::uint8_t ack[64];
    pollfd wait{fd_, POLLIN, 0};
    if (::poll(&wait, 1, 2000) != 1) return false;
    return ::recv(fd_, ack, sizeof(ack), 0) >= 12 && ack[0] == 0 && ack[1] == 0;
  }

 private:
  int fd_ = -1;
  std::uint16_t port_ = 0;
  std::uint8_t id_ = 0;
};

sim::RigPhysics VirtualPhysics(const char* serial) {
  sim::RigPhysics physics;
  physics.time_scale = 10.0;
  physics.camera.serial = serial;
  return physics;
}

// Another application holds the control channel: nothing is written, and it is named by the
// address and port the camera's primary application registers hold.
TEST(AravisConfigureVirtualCamera, ACameraControlledByAnotherApplicationIsRefusedNamingIt) {
  testing::LoopbackGvcpLock lock;
  const sim::RigPhysics physics = VirtualPhysics("IRDCFG02");
  sim::World world(physics.time_scale);
  sim::CameraServer server(world, physics);
  server.Start();
  RawApplication other;
  ASSERT_TRUE(other.Write(0x0a00, 2));  // control privilege
  try {
    AravisCamera::Open("127.0.0.1", "IRDCFG02");
    FAIL() << "opened a camera another application controls";
  } catch (const CameraError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("controlled by the application at 127.0.0.1 port " +
                        std::to_string(other.port())),
              std::string::npos)
        << what;
  }
  ASSERT_TRUE(other.Write(0x0a00, 0));  // released
  EXPECT_NO_THROW(AravisCamera::Open("127.0.0.1", "IRDCFG02"));
}

// A previous client (crashed) left the camera free-running: opening it stops the acquisition.
TEST(AravisConfigureVirtualCamera, OpeningStopsAnAcquisitionLeftRunning) {
  testing::LoopbackGvcpLock lock;
  const sim::RigPhysics physics = VirtualPhysics("IRDCFG03");
  sim::World world(physics.time_scale);
  sim::CameraServer server(world, physics);
  server.Start();
  {
    RawApplication previous;
    ASSERT_TRUE(previous.Write(0x0124, 1));  // AcquisitionStart, free-running at 25 frames/s
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(150));
  ASSERT_GT(server.FramesExposed(), 0u) << "the previous client's acquisition never ran";
  const auto camera = AravisCamera::Open("127.0.0.1", "IRDCFG03");
  std::this_thread::sleep_for(std::chrono::milliseconds(100));  // a frame under way ends
  const std::uint64_t after_open = server.FramesExposed();
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  EXPECT_EQ(server.FramesExposed(), after_open) << "still acquiring after Open";
}

}  // namespace
}  // namespace irdist
