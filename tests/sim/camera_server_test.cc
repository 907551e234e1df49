#include "sim/camera_server.h"

#include <arpa/inet.h>
#include <arv.h>
#include <net/if.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "sim/renderer.h"
#include "sim/trajectory_file.h"
#include "tests/loopback_gvcp.h"
#include "tests/sim/station_on_world.h"

namespace irdist::sim {
namespace {

template <typename T>
struct GUnref {
  void operator()(T* p) const {
    if (p != nullptr) g_object_unref(p);
  }
};
template <typename T>
using GPtr = std::unique_ptr<T, GUnref<T>>;

#define ASSERT_NO_GERROR(error)                                   \
  do {                                                            \
    GError* e_ = (error);                                         \
    ASSERT_EQ(e_, nullptr) << (e_ != nullptr ? e_->message : ""); \
  } while (false)

constexpr char kSerial[] = "IRDTEST042";

RigPhysics TestPhysics() {
  RigPhysics p;
  p.time_scale = 10.0;
  p.camera.serial = kSerial;
  p.emitter.thermal_resistance_k_per_w = 0.0;  // no drift: frames compare against one truth
  return p;
}

// Background-subtracted Mono12 gray-level sum of an 80x80 box around the image centre.
double SignalSum(ArvBuffer* buffer) {
  size_t size = 0;
  const void* data = arv_buffer_get_data(buffer, &size);
  const int w = arv_buffer_get_image_width(buffer), h = arv_buffer_get_image_height(buffer);
  const cv::Mat frame(h, w, CV_16UC1, const_cast<void*>(data));
  cv::Mat box, band;
  frame(cv::Rect(w / 2 - 40, h / 2 - 40, 80, 80)).convertTo(box, CV_64F);
  frame(cv::Rect(0, 0, w, 100)).convertTo(band, CV_64F);
  return cv::sum(box)[0] - cv::mean(band)[0] * 6400;
}

class CameraServerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(irdist::testing::WaitForLoopbackGvcpPort(std::chrono::seconds(120)))
        << "127.0.0.1:3956 stayed busy: another fake camera is running";
    world_.SetPose(2000, 0, 0, false);
    world_.SetCurrent(500);
    server_ = std::make_unique<CameraServer>(world_, physics_);
    server_->Start();
    GError* error = nullptr;
    camera_.reset(arv_camera_new("127.0.0.1", &error));
    ASSERT_NO_GERROR(error);
    ASSERT_NE(camera_, nullptr);
  }
  void TearDown() override {
    if (stream_ && camera_) arv_camera_stop_acquisition(camera_.get(), nullptr);
    stream_.reset();
    camera_.reset();
    server_.reset();
  }

  // Stream on loopback as on the virtual rig: no packet socket, fixed 4 MB socket buffer.
  void CreateStream() {
    arv_camera_gv_set_stream_options(camera_.get(), ARV_GV_STREAM_OPTION_PACKET_SOCKET_DISABLED);
    GError* error = nullptr;
    stream_.reset(arv_camera_create_stream(camera_.get(), nullptr, nullptr, &error));
    ASSERT_NO_GERROR(error);
    g_object_set(stream_.get(), "socket-buffer", ARV_GV_STREAM_SOCKET_BUFFER_FIXED,
                 "socket-buffer-size", 4 << 20, nullptr);
    const guint payload = arv_camera_get_payload(camera_.get(), &error);
    ASSERT_NO_GERROR(error);
    for (int i = 0; i < 8; ++i)
      arv_stream_push_buffer(stream_.get(), arv_buffer_new(payload, nullptr));
  }

  // Pops one buffer; returns nullptr on timeout, re-queues it after `use`.
  template <typename F>
  bool Pop(guint64 timeout_us, F use) {
    ArvBuffer* buffer = arv_stream_timeout_pop_buffer(stream_.get(), timeout_us);
    if (buffer == nullptr) return false;
    const bool ok = arv_buffer_get_status(buffer) == ARV_BUFFER_STATUS_SUCCESS;
    if (ok) use(buffer);
    arv_stream_push_buffer(stream_.get(), buffer);
    return ok;
  }

  // Line1-triggered frames (the acquisition started so), one per exposure, each exposed for the
  // exposure set before its pulse: its signal the renderer's truth for that exposure (within 2%),
  // its record that exposure in Mono12.
  void ExpectLine1FramesCarryTheirExposures() {
    GError* error = nullptr;
    const Renderer truth_renderer(physics_);
    PoseState pose;
    pose.slide_mm = 2000;
    pose.bias_ma = 500;
    const double k = physics_.sensor.system_gain_dn_per_e;
    for (double exposure_us : {8000.0, 30000.0, 12000.0, 36000.0, 20000.0, 32000.0}) {
      SCOPED_TRACE("exposure " + std::to_string(exposure_us) + " us");
      arv_camera_set_exposure_time(camera_.get(), exposure_us, &error);
      ASSERT_NO_GERROR(error);
      world_.FireTrigger();
      double sum = 0.0;
      ASSERT_TRUE(Pop(2000000, [&](ArvBuffer* b) { sum = SignalSum(b); }))
          << "no frame for the trigger at " << exposure_us << " us";
      const double expected =
          k * truth_renderer.Describe(pose, exposure_us * 1e-6, PixelFormat::kMono12).signal_e;
      EXPECT_NEAR(sum / expected, 1.0, 0.02) << "exposure " << exposure_us << " us";
      const std::vector<FrameRecord> records = server_->RecentFrames();
      ASSERT_FALSE(records.empty());
      EXPECT_EQ(records.back().exposure_us, exposure_us);
      EXPECT_EQ(records.back().format, "Mono12");
    }
  }

  // Software-triggered Mono12 frames of the 256 x 256 region at (512, 384), 8 ms each: the stream
  // created and the acquisition started.
  void StartSoftwareTriggeredMono12Region() {
    GError* error = nullptr;
    arv_camera_set_pixel_format_from_string(camera_.get(), "Mono12", &error);
    ASSERT_NO_GERROR(error);
    arv_camera_set_region(camera_.get(), 512, 384, 256, 256, &error);
    ASSERT_NO_GERROR(error);
    arv_camera_set_exposure_time(camera_.get(), 8000.0, &error);
    ASSERT_NO_GERROR(error);
    arv_camera_set_string(camera_.get(), "TriggerMode", "On", &error);
    ASSERT_NO_GERROR(error);
    arv_camera_set_string(camera_.get(), "TriggerSource", "Software", &error);
    ASSERT_NO_GERROR(error);
    CreateStream();
    arv_camera_start_acquisition(camera_.get(), &error);
    ASSERT_NO_GERROR(error);
  }

  RigPhysics physics_ = TestPhysics();
  World world_{physics_.time_scale};
  std::unique_ptr<CameraServer> server_;
  GPtr<ArvCamera> camera_;
  GPtr<ArvStream> stream_;
};

TEST_F(CameraServerTest, OpensByAddressWithItsSerialAndFeatures) {
  GError* error = nullptr;
  const char* serial = arv_camera_get_device_serial_number(camera_.get(), &error);
  ASSERT_NO_GERROR(error);
  EXPECT_STREQ(serial, kSerial);
  EXPECT_EQ(server_->device_id(), std::string("Aravis-Fake-") + kSerial);
  EXPECT_STREQ(arv_camera_get_vendor_name(camera_.get(), nullptr), "Aravis");
  EXPECT_STREQ(arv_camera_get_model_name(camera_.get(), nullptr), "Fake");

  // Factory defaults: full sensor, free-running.
  gint x, y, w, h;
  arv_camera_get_region(camera_.get(), &x, &y, &w, &h, &error);
  ASSERT_NO_GERROR(error);
  EXPECT_EQ(w, 1280);
  EXPECT_EQ(h, 1024);
  EXPECT_STREQ(arv_camera_get_string(camera_.get(), "TriggerMode", &error), "Off");
  ASSERT_NO_GERROR(error);

  arv_camera_set_pixel_format_from_string(camera_.get(), "Mono12", &error);
  ASSERT_NO_GERROR(error);
  EXPECT_STREQ(arv_camera_get_pixel_format_as_string(camera_.get(), nullptr), "Mono12");
  arv_camera_set_float(camera_.get(), "ExposureTime", 32000.0, &error);
  ASSERT_NO_GERROR(error);
  EXPECT_DOUBLE_EQ(arv_camera_get_exposure_time(camera_.get(), &error), 32000.0);
  guint n = 0;
  const char** sources =
      arv_camera_dup_available_enumerations_as_strings(camera_.get(), "TriggerSource", &n, &error);
  ASSERT_NO_GERROR(error);
  std::vector<std::string> names(sources, sources + n);
  g_free(sources);
  EXPECT_NE(std::find(names.begin(), names.end(), "Line1"), names.end());
  EXPECT_NE(std::find(names.begin(), names.end(), "Software"), names.end());
  arv_camera_set_string(camera_.get(), "TriggerSource", "Line1", &error);
  ASSERT_NO_GERROR(error);
  EXPECT_STREQ(arv_camera_get_string(camera_.get(), "TriggerSource", &error), "Line1");
  arv_camera_set_string(camera_.get(), "TriggerMode", "On", &error);
  ASSERT_NO_GERROR(error);
  EXPECT_STREQ(arv_camera_get_string(camera_.get(), "TriggerMode", &error), "On");
  EXPECT_NEAR(arv_camera_get_float(camera_.get(), "DeviceTemperature", &error),
              physics_.sensor.temperature_c, 1e-3);
  ASSERT_NO_GERROR(error);
}

// Free-running at power-up; then Line1-triggered frames, each with the exposure set for it.
TEST_F(CameraServerTest, TriggeredFramesCarryTheExposureSetForThem) {
  GError* error = nullptr;
  arv_camera_set_pixel_format_from_string(camera_.get(), "Mono12", &error);
  ASSERT_NO_GERROR(error);
  CreateStream();
  arv_camera_start_acquisition(camera_.get(), &error);
  ASSERT_NO_GERROR(error);
  int free_frames = 0;
  for (int i = 0; i < 20 && free_frames < 3; ++i) {
    if (Pop(500000, [](ArvBuffer*) {})) ++free_frames;
  }
  EXPECT_EQ(free_frames, 3) << "no free-running frames at power-up";
  arv_camera_stop_acquisition(camera_.get(), &error);
  ASSERT_NO_GERROR(error);
  // Every buffer left, complete or not (a loaded host may time some out).
  while (ArvBuffer* left = arv_stream_timeout_pop_buffer(stream_.get(), 100000)) {
    arv_stream_push_buffer(stream_.get(), left);
  }

  arv_camera_set_string(camera_.get(), "TriggerMode", "On", &error);
  ASSERT_NO_GERROR(error);
  arv_camera_set_string(camera_.get(), "TriggerSource", "Line1", &error);
  ASSERT_NO_GERROR(error);
  arv_camera_start_acquisition(camera_.get(), &error);
  ASSERT_NO_GERROR(error);

  ASSERT_NO_FATAL_FAILURE(ExpectLine1FramesCarryTheirExposures());
  EXPECT_EQ(server_->LinePulsesAccepted(), 6u);

  // A Line1 pulse does nothing while the source is Software; the software trigger does.
  arv_camera_set_string(camera_.get(), "TriggerSource", "Software", &error);
  ASSERT_NO_GERROR(error);
  world_.FireTrigger();
  EXPECT_FALSE(Pop(300000, [](ArvBuffer*) {}));
  arv_camera_software_trigger(camera_.get(), &error);
  ASSERT_NO_GERROR(error);
  EXPECT_TRUE(Pop(2000000, [](ArvBuffer*) {}));

  // Fault: a dropped frame never arrives; the next one does.
  server_->SetDropFrameRate(1.0);
  arv_camera_software_trigger(camera_.get(), &error);
  EXPECT_FALSE(Pop(400000, [](ArvBuffer*) {}));
  EXPECT_EQ(server_->FramesDropped(), 1u);
  server_->SetDropFrameRate(0.0);
  arv_camera_software_trigger(camera_.get(), &error);
  EXPECT_TRUE(Pop(2000000, [](ArvBuffer*) {}));
}

// The control channel answers while a frame is exposed and read out, as a real camera's does: a
// register read made during a long exposure returns before that frame arrives.
TEST_F(CameraServerTest, ServesControlRequestsWhileAFrameIsExposedAndReadOut) {
  GError* error = nullptr;
  arv_camera_set_string(camera_.get(), "TriggerMode", "On", &error);
  ASSERT_NO_GERROR(error);
  arv_camera_set_string(camera_.get(), "TriggerSource", "Software", &error);
  ASSERT_NO_GERROR(error);
  arv_camera_set_exposure_time(camera_.get(), 900000.0, &error);  // 90 ms of host time at 10x
  ASSERT_NO_GERROR(error);
  arv_camera_set_region(camera_.get(), 0, 0, 256, 256, &error);
  ASSERT_NO_GERROR(error);
  CreateStream();
  arv_camera_start_acquisition(camera_.get(), &error);
  ASSERT_NO_GERROR(error);
  const std::uint64_t before = server_->Stats().requests_during_frame;
  arv_camera_software_trigger(camera_.get(), &error);
  ASSERT_NO_GERROR(error);
  while (server_->FramesExposed() == 0 && server_->Stats().requests_during_frame == before) {
    EXPECT_DOUBLE_EQ(arv_camera_get_exposure_time(camera_.get(), &error), 900000.0);
    ASSERT_NO_GERROR(error);
  }
  // Read during the frame: the frame is not there yet.
  EXPECT_GT(server_->Stats().requests_during_frame, before);
  EXPECT_EQ(arv_stream_try_pop_buffer(stream_.get()), nullptr);
  ArvBuffer* buffer = arv_stream_timeout_pop_buffer(stream_.get(), 3000000);
  ASSERT_NE(buffer, nullptr);
  EXPECT_EQ(arv_buffer_get_status(buffer), ARV_BUFFER_STATUS_SUCCESS);
  arv_stream_push_buffer(stream_.get(), buffer);
}

// With ChunkModeActive, each frame carries ChunkExposureTime: the exposure it was taken with,
// even when the next exposure was written while it was read out.
TEST_F(CameraServerTest, ChunkExposureTimeIsTheExposureEachFrameWasTakenWith) {
  GError* error = nullptr;
  ASSERT_TRUE(arv_camera_are_chunks_available(camera_.get(), &error));
  arv_camera_set_chunks(camera_.get(), "ExposureTime", &error);
  ASSERT_NO_GERROR(error);
  arv_camera_set_string(camera_.get(), "TriggerMode", "On", &error);
  ASSERT_NO_GERROR(error);
  arv_camera_set_string(camera_.get(), "TriggerSource", "Software", &error);
  ASSERT_NO_GERROR(error);
  arv_camera_set_region(camera_.get(), 0, 0, 256, 256, &error);
  ASSERT_NO_GERROR(error);
  CreateStream();
  GPtr<ArvChunkParser> parser(arv_camera_create_chunk_parser(camera_.get()));
  ASSERT_NE(parser, nullptr);
  arv_camera_start_acquisition(camera_.get(), &error);
  ASSERT_NO_GERROR(error);
  for (double exposure_us : {8000.0, 30000.0, 12000.0}) {
    arv_camera_set_exposure_time(camera_.get(), exposure_us, &error);
    ASSERT_NO_GERROR(error);
    arv_camera_software_trigger(camera_.get(), &error);
    ASSERT_NO_GERROR(error);
    arv_camera_set_exposure_time(camera_.get(), 50000.0, &error);  // while it is exposed
    ASSERT_NO_GERROR(error);
    double chunk_us = 0.0;
    ASSERT_TRUE(Pop(2000000, [&](ArvBuffer* b) {
      ASSERT_TRUE(arv_buffer_has_chunks(b));
      GError* e = nullptr;
      chunk_us = arv_chunk_parser_get_float_value(parser.get(), b, "ChunkExposureTime", &e);
      ASSERT_NO_GERROR(e);
    }));
    // The camera latches the exposure when the frame starts: under load the software trigger may
    // still be queued when 50000 is written. Either way the chunk must say what the frame was
    // taken with, as the camera itself recorded it.
    const std::vector<FrameRecord> records = server_->RecentFrames();
    ASSERT_FALSE(records.empty());
    EXPECT_DOUBLE_EQ(chunk_us, records.back().exposure_us);
    EXPECT_TRUE(chunk_us == exposure_us || chunk_us == 50000.0) << chunk_us;
  }
}

// Lost GVSP packets are sent again on the grabber's request: every frame completes.
TEST_F(CameraServerTest, ResendsLostPacketsOnRequest) {
  GError* error = nullptr;
  arv_camera_set_string(camera_.get(), "TriggerMode", "On", &error);
  ASSERT_NO_GERROR(error);
  arv_camera_set_string(camera_.get(), "TriggerSource", "Software", &error);
  ASSERT_NO_GERROR(error);
  server_->SetLostPacketRatio(0.05);
  CreateStream();
  // Resends take round trips: on a loaded host give each frame 1 s (this is not a timing test).
  // Aravis enlarges the socket buffer only when the first frame starts, so that frame's burst can
  // overflow the default buffer: a long run is lost at once, more than the default request ratio
  // (25 % of the frame) lets Aravis ask again, and the frame timed out (about 1 run in 4). Let it
  // ask for up to the whole frame: those packets still come only from the camera's resends.
  g_object_set(stream_.get(), "frame-retention", 1000000u, "packet-request-ratio", 1.0, nullptr);
  arv_camera_start_acquisition(camera_.get(), &error);
  ASSERT_NO_GERROR(error);
  int complete = 0;
  for (int i = 0; i < 5; ++i) {
    arv_camera_software_trigger(camera_.get(), &error);
    ASSERT_NO_GERROR(error);
    if (Pop(3000000, [](ArvBuffer*) {})) ++complete;
  }
  EXPECT_EQ(complete, 5);
  EXPECT_GT(server_->Stats().packets_lost, 0u);
  EXPECT_GT(server_->Stats().resend_requests, 0u);
  EXPECT_GT(server_->Stats().packets_resent, 0u);
}

// Pixel n of a Mono12 frame's data (two bytes, little-endian) or of a Mono12p one's (PFNC: an
// LSB-first 12-bit stream, two pixels in three bytes).
int Mono12PixelValue(const std::uint8_t* b, int n, bool packed) {
  if (!packed) return b[2 * n] | (b[2 * n + 1] << 8);
  if (n % 2 == 0) return b[3 * (n / 2)] | ((b[3 * (n / 2) + 1] & 0x0f) << 8);
  return (b[3 * (n / 2) + 1] >> 4) | (b[3 * (n / 2) + 2] << 4);
}

// Mono12p (PFNC): each frame is the Mono12 frame's values as an LSB-first 12-bit stream, two
// pixels in three bytes: unpacked by the layout, the packed frame matches a Mono12 frame of the
// same scene.
TEST_F(CameraServerTest, Mono12pFramesAreTheMono12ValuesPackedLsbFirst) {
  GError* error = nullptr;
  arv_camera_set_region(camera_.get(), 600, 480, 96, 64, &error);
  ASSERT_NO_GERROR(error);
  arv_camera_set_string(camera_.get(), "TriggerMode", "On", &error);
  ASSERT_NO_GERROR(error);
  arv_camera_set_string(camera_.get(), "TriggerSource", "Software", &error);
  ASSERT_NO_GERROR(error);
  cv::Mat sums[2];
  for (const char* format : {"Mono12", "Mono12p"}) {
    stream_.reset();
    arv_camera_set_pixel_format_from_string(camera_.get(), format, &error);
    ASSERT_NO_GERROR(error);
    const bool packed = std::string(format) == "Mono12p";
    EXPECT_EQ(arv_camera_get_payload(camera_.get(), nullptr), packed ? 96u * 64 * 3 / 2 : 96u * 64 * 2);
    CreateStream();
    arv_camera_start_acquisition(camera_.get(), &error);
    ASSERT_NO_GERROR(error);
    cv::Mat sum(64, 96, CV_64F, cv::Scalar(0));
    for (int i = 0; i < 4; ++i) {
      arv_camera_software_trigger(camera_.get(), &error);
      ASSERT_NO_GERROR(error);
      ASSERT_TRUE(Pop(3000000, [&](ArvBuffer* buffer) {
        size_t size = 0;
        const auto* b = static_cast<const std::uint8_t*>(arv_buffer_get_image_data(buffer, &size));
        EXPECT_EQ(static_cast<std::uint32_t>(arv_buffer_get_image_pixel_format(buffer)),
                  packed ? 0x010c0047u : 0x01100005u);
        for (int n = 0; n < 96 * 64; ++n) {
          const int value = Mono12PixelValue(b, n, packed);
          EXPECT_LE(value, 4095);
          sum.at<double>(n / 96, n % 96) += value;
        }
      }));
    }
    arv_camera_stop_acquisition(camera_.get(), &error);
    ASSERT_NO_GERROR(error);
    sums[packed ? 1 : 0] = sum;
  }
  // The same scene: the IRED's image in the same place with the same signal (noise apart).
  cv::Point2d centre[2];
  for (int k = 0; k < 2; ++k) {
    double peak = 0.0;
    cv::minMaxLoc(sums[k], nullptr, &peak);
    cv::Mat blob;
    cv::threshold(sums[k], blob, 0.5 * peak, 0.0, cv::THRESH_TOZERO);
    const cv::Moments m = cv::moments(blob);
    ASSERT_GT(m.m00, 0.0);
    centre[k] = {m.m10 / m.m00, m.m01 / m.m00};
  }
  EXPECT_NEAR(centre[1].x, centre[0].x, 0.5);
  EXPECT_NEAR(centre[1].y, centre[0].y, 0.5);
  EXPECT_NEAR(cv::sum(sums[1])[0], cv::sum(sums[0])[0], 0.02 * cv::sum(sums[0])[0]);
}

// A camera without resend: no PACKETRESEND capability declared and no packet sent again.
TEST_F(CameraServerTest, WithoutResendLostPacketsStayLost) {
  server_->SetPacketResend(false);
  guint32 capability = 0;
  GError* error = nullptr;
  arv_device_read_register(arv_camera_get_device(camera_.get()), 0x934, &capability, &error);
  ASSERT_NO_GERROR(error);
  EXPECT_EQ(capability & (1u << 2), 0u);
  arv_camera_set_string(camera_.get(), "TriggerMode", "On", &error);
  ASSERT_NO_GERROR(error);
  arv_camera_set_string(camera_.get(), "TriggerSource", "Software", &error);
  ASSERT_NO_GERROR(error);
  server_->SetLostPacketRatio(0.05);
  CreateStream();
  g_object_set(stream_.get(), "packet-resend", ARV_GV_STREAM_PACKET_RESEND_ALWAYS, nullptr);
  arv_camera_start_acquisition(camera_.get(), &error);
  ASSERT_NO_GERROR(error);
  int complete = 0;
  for (int i = 0; i < 3; ++i) {
    arv_camera_software_trigger(camera_.get(), &error);
    ASSERT_NO_GERROR(error);
    if (Pop(3000000, [](ArvBuffer*) {})) ++complete;
  }
  EXPECT_EQ(complete, 0);  // a full frame is ~1900 packets: none arrives whole at 5% loss
  EXPECT_GT(server_->Stats().packets_lost, 0u);
  EXPECT_EQ(server_->Stats().packets_resent, 0u);
}

// Only loopback in this network namespace: discovery (a broadcast) reaches nothing else.
bool OnlyLoopback() {
  struct if_nameindex* names = if_nameindex();
  if (names == nullptr) return false;
  bool only = true;
  for (auto* n = names; n->if_index != 0; ++n) only = only && std::string(n->if_name) == "lo";
  if_freenameindex(names);
  return only;
}

// GigE Vision discovery (a DISCOVERY_CMD broadcast to 255.255.255.255:3956) finds the camera by
// name on the loopback interface, as arv-tool-0.8 and `irdist devices --discover` look for it.
TEST_F(CameraServerTest, AnswersDiscoveryOnItsInterface) {
  if (!OnlyLoopback()) GTEST_SKIP() << "discovery broadcasts: run in a network namespace (unshare -n)";
  arv_update_device_list();
  bool found = false;
  for (unsigned int i = 0; i < arv_get_n_devices(); ++i) {
    if (server_->device_id() == arv_get_device_id(i)) {
      found = true;
      EXPECT_STREQ(arv_get_device_address(i), "127.0.0.1");
      EXPECT_STREQ(arv_get_device_serial_nbr(i), kSerial);
    }
  }
  EXPECT_TRUE(found) << server_->device_id() << " not discovered";
}

// Sends one GVCP WRITEREG command from `fd` to 127.0.0.1:3956 and waits for its acknowledge.
bool WriteRegisterRaw(int fd, std::uint32_t address, std::uint32_t value, std::uint16_t id) {
  const std::uint8_t packet[] = {0x42, 0x01, 0x00, 0x82, 0x00, 0x08,
                                 static_cast<std::uint8_t>(id >> 8), static_cast<std::uint8_t>(id),
                                 static_cast<std::uint8_t>(address >> 24),
                                 static_cast<std::uint8_t>(address >> 16),
                                 static_cast<std::uint8_t>(address >> 8),
                                 static_cast<std::uint8_t>(address),
                                 static_cast<std::uint8_t>(value >> 24),
                                 static_cast<std::uint8_t>(value >> 16),
                                 static_cast<std::uint8_t>(value >> 8),
                                 static_cast<std::uint8_t>(value)};
  sockaddr_in camera{};
  camera.sin_family = AF_INET;
  camera.sin_port = htons(3956);
  camera.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::sendto(fd, packet, sizeof(packet), 0, reinterpret_cast<sockaddr*>(&camera),
               sizeof(camera)) != static_cast<ssize_t>(sizeof(packet))) {
    return false;
  }
  std::uint8_t ack[64];
  pollfd wait{fd, POLLIN, 0};
  if (::poll(&wait, 1, 2000) != 1) return false;
  const ssize_t got = ::recv(fd, ack, sizeof(ack), 0);
  return got >= 12 && ack[0] == 0 && ack[1] == 0 && ack[3] == 0x83;  // status 0, WRITEREG_ACK
}

// A controller that takes the camera and then falls silent (a client killed while connected)
// loses its control privilege after its heartbeat timeout, so the next client can take over.
TEST(CameraServerHeartbeat, SilentControllerLosesControlAfterItsHeartbeatTimeout) {
  ASSERT_TRUE(irdist::testing::WaitForLoopbackGvcpPort(std::chrono::seconds(120)));
  RigPhysics physics = TestPhysics();
  World world(physics.time_scale);
  CameraServer server(world, physics);
  server.Start();
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  ASSERT_GE(fd, 0);
  ASSERT_TRUE(WriteRegisterRaw(fd, 0x938, 300, 1));  // heartbeat timeout 300 ms
  ASSERT_TRUE(WriteRegisterRaw(fd, 0xa00, 2, 2));    // control privilege
  ASSERT_TRUE(WriteRegisterRaw(fd, 0x124, 1, 3));    // AcquisitionStart
  // Another application may not write while the controller is alive.
  GError* error = nullptr;
  GPtr<ArvCamera> other(arv_camera_new("127.0.0.1", &error));
  if (error != nullptr) g_clear_error(&error);
  if (other != nullptr) {
    arv_camera_set_exposure_time(other.get(), 20000.0, &error);
    EXPECT_NE(error, nullptr) << "a second application wrote while the controller was alive";
    if (error != nullptr) g_clear_error(&error);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(800));  // the controller is silent
  ::close(fd);
  EXPECT_EQ(server.Stats().controllers_expired, 1u);
  other.reset();
  GPtr<ArvCamera> next(arv_camera_new("127.0.0.1", &error));
  ASSERT_NO_GERROR(error);
  arv_camera_set_exposure_time(next.get(), 12345.0, &error);
  ASSERT_NO_GERROR(error);
  EXPECT_DOUBLE_EQ(arv_camera_get_exposure_time(next.get(), &error), 12345.0);
}

TEST(CameraServerPort, SecondCameraOnLoopbackFailsClearly) {
  ASSERT_TRUE(irdist::testing::WaitForLoopbackGvcpPort(std::chrono::seconds(120)));
  RigPhysics physics = TestPhysics();
  World world(physics.time_scale);
  CameraServer first(world, physics);
  first.Start();
  CameraServer second(world, physics);
  try {
    second.Start();
    ADD_FAILURE() << "a second fake camera started on 127.0.0.1";
  } catch (const CameraServerError& e) {
    EXPECT_NE(std::string(e.what()).find("3956"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(first.running());
  EXPECT_FALSE(second.running());
}

// The blob's intensity-weighted width (2 sigma along x, px) in a Mono12 frame and its standard
// deviation from the frame's noise: the moments of a box around the blob's centre reaching
// `reach_px` from it, less the frame's median (black level and dark signal). Each pixel's
// variance is the background's (from the median absolute deviation) plus its shot noise. The
// centre is the centroid of the pixels above half the peak: the brightest pixel of a flat-topped
// disc lies anywhere on it, and a box around one near the edge cut the far side off (a width
// 4.6 sd small on 1 frame of 40, 2026-12-04).
struct Width {
  double px = 0.0, sd_px = 0.0;
};
Width BlobWidth(ArvBuffer* buffer, int reach_px, double gain_dn_per_e) {
  size_t size = 0;
  const void* data = arv_buffer_get_data(buffer, &size);
  const int w = arv_buffer_get_image_width(buffer), h = arv_buffer_get_image_height(buffer);
  cv::Mat frame;
  cv::Mat(h, w, CV_16UC1, const_cast<void*>(data)).convertTo(frame, CV_64F);
  cv::Point peak;
  cv::minMaxLoc(frame, nullptr, nullptr, nullptr, &peak);
  const auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  const double background = median(std::vector<double>(frame.begin<double>(), frame.end<double>()));
  std::vector<double> deviations;
  for (auto it = frame.begin<double>(); it != frame.end<double>(); ++it) {
    deviations.push_back(std::fabs(*it - background));
  }
  const double background_var = std::pow(1.4826 * median(deviations), 2);
  const double half = 0.5 * (background + frame.at<double>(peak));
  cv::Mat mask;
  cv::compare(frame, half, mask, cv::CMP_GT);
  const cv::Moments m = cv::moments(mask, true);
  const cv::Point centre = m.m00 > 0.0 ? cv::Point(static_cast<int>(std::lround(m.m10 / m.m00)),
                                                    static_cast<int>(std::lround(m.m01 / m.m00)))
                                        : peak;
  const cv::Rect box = cv::Rect(centre.x - reach_px, centre.y - reach_px, 2 * reach_px + 1,
                                2 * reach_px + 1) & cv::Rect(0, 0, w, h);
  double sum = 0.0, sx = 0.0, sxx = 0.0;
  for (int r = box.y; r < box.y + box.height; ++r) {
    for (int c = box.x; c < box.x + box.width; ++c) {
      const double e = frame.at<double>(r, c) - background;
      sum += e;
      sx += e * c;
      sxx += e * c * c;
    }
  }
  const double mean = sx / sum, m2 = sxx / sum - mean * mean;
  double var_m2 = 0.0;  // of sum_i e_i ((x_i - mean)^2 - m2) / sum, to first order
  for (int r = box.y; r < box.y + box.height; ++r) {
    for (int c = box.x; c < box.x + box.width; ++c) {
      const double e = std::max(frame.at<double>(r, c) - background, 0.0);
      const double lever = ((c - mean) * (c - mean) - m2) / sum;
      var_m2 += (background_var + gain_dn_per_e * e) * lever * lever;
    }
  }
  return {2.0 * std::sqrt(m2), std::sqrt(var_m2 / m2)};  // d(2 sqrt(m2)) = d(m2) / sqrt(m2)
}

// A frame taken during the slide's move: its block id, its GigE timestamp and its blob's width.
struct Shot {
  guint64 frame_id, timestamp_ns;
  Width width;
};

// The width (px) the renderer gives the blob of an 8 ms Mono12 frame at 500 mA at the frame's
// recorded mid-exposure slide position and junction rise.
double MidExposureWidthPx(const Renderer& truth_renderer, const FrameRecord& record) {
  PoseState mid;
  mid.slide_mm = record.slide_mm;
  mid.bias_ma = 500;
  return truth_renderer.Describe(mid, 0.008, PixelFormat::kMono12, record.junction_rise_k).width_px;
}

// docs/virtual-rig.md "Truth of a moving target": frames taken while the slide moves 1500 ->
// 3000 mm at 0.5 m/s carry the IRED's pose at the middle of their exposure (the profile written
// out by hand), their GigE timestamp is the exposure's start on the world's clock in ns, the
// trajectory file gives the same truth from timestamp and exposure, and the image's blob has the
// mid-exposure pose's size.
TEST_F(CameraServerTest, FramesDuringASlideMoveCarryTheirMidExposureTruth) {
  const std::string path = "/tmp/irdist-camera-trajectory-" + std::to_string(::getpid()) + ".csv";
  ::unlink(path.c_str());
  world_.LogTrajectory(path);
  testing::StationOnWorld station(world_, testing::HalfMetrePerSecond());
  ASSERT_EQ(station.Do("HOME"), "OK");
  ASSERT_TRUE(station.WaitFor("IDLE", std::chrono::seconds(30)));
  ASSERT_EQ(station.Do("MOVE 150000,0,0"), "OK");
  ASSERT_EQ(station.Do("SOUR:CURR 50000"), "OK");  // 500 mA (the power-up turned it off)
  ASSERT_TRUE(station.WaitFor("IDLE", std::chrono::seconds(30)));
  ASSERT_NO_FATAL_FAILURE(StartSoftwareTriggeredMono12Region());
  GError* error = nullptr;
  std::vector<Shot> shots;
  double move_s = 0.0;
  ASSERT_EQ(station.Do("MOVE 300000,0,0", &move_s), "OK");
  while (world_.clock().Now() < move_s + 3.7) {
    arv_camera_software_trigger(camera_.get(), &error);
    ASSERT_NO_GERROR(error);
    Pop(2000000, [&](ArvBuffer* b) {
      // At 1.5 m the disc's image reaches 10 px from its centre; 7 px more hold its blur.
      shots.push_back({arv_buffer_get_frame_id(b), arv_buffer_get_timestamp(b),
                       BlobWidth(b, 17, physics_.sensor.system_gain_dn_per_e)});
    });
  }
  const std::vector<FrameRecord> records = server_->RecentFrames();
  const Trajectory logged = ReadTrajectoryFile(path);
  const Renderer truth_renderer(physics_);
  int cruising = 0;
  for (const Shot& shot : shots) {
    const auto record = std::find_if(records.begin(), records.end(), [&](const FrameRecord& r) {
      return r.block_id == shot.frame_id;
    });
    ASSERT_NE(record, records.end()) << "block " << shot.frame_id;
    EXPECT_EQ(shot.timestamp_ns, record->timestamp_ns);
    EXPECT_EQ(record->timestamp_ns, SimTimeToNs(record->sim_time_s));
    const double tau = record->sim_time_s + 0.5 * record->exposure_us * 1e-6 - move_s;
    ASSERT_TRUE(record->truth_from_trajectory);
    EXPECT_NEAR(record->slide_mm, testing::ExpectedSlideMm(tau), 1e-6) << "tau " << tau;
    EXPECT_NEAR(record->slide_mm_s, testing::ExpectedSlideMmS(tau), 1e-6) << "tau " << tau;
    const TrajectoryPoint looked_up = MidExposure(logged, shot.timestamp_ns, 8000.0);
    EXPECT_NEAR(looked_up.slide_mm, record->slide_mm, 1e-5) << "tau " << tau;
    EXPECT_NEAR(looked_up.slide_mm_s, record->slide_mm_s, 1e-5) << "tau " << tau;
    const double expected_px = MidExposureWidthPx(truth_renderer, *record);
    EXPECT_NEAR(shot.width.px, expected_px, 4.0 * shot.width.sd_px) << "tau " << tau;
    if (tau > 0.5 && tau < 3.0) ++cruising;
    std::printf("tau %.4f slide %.3f mm width %.4f +- %.4f px expected %.4f z %.2f\n", tau,
                record->slide_mm, shot.width.px, shot.width.sd_px, expected_px,
                (shot.width.px - expected_px) / shot.width.sd_px);
  }
  EXPECT_GE(cruising, 5) << "too few frames during the cruise to mean anything";
  ::unlink(path.c_str());
}

}  // namespace
}  // namespace irdist::sim
