#include "sim/camera_server.h"

#include <arpa/inet.h>
#include <arv.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <deque>
#include <mutex>
#include <random>
#include <thread>

#include "sim/renderer.h"

namespace irdist::sim {
namespace internal {
extern const char* const kVirtualCameraXml;
}  // namespace internal

namespace {

// Registers of the fake camera (ArvFakeCamera's map, plus ours from sim/virtual_camera.xml).
constexpr guint32 kRegWidth = 0x100;
constexpr guint32 kRegHeight = 0x104;
constexpr guint32 kRegSensorHeight = 0x118;
constexpr guint32 kRegSensorWidth = 0x11c;
constexpr guint32 kRegTriggerMode = 0x300;
constexpr guint32 kRegTriggerSource = 0x304;  // pinned to 1 (Software): the fake's own check
constexpr guint32 kRegTriggerSoftware = 0x30c;
constexpr guint32 kRegTriggerSourceShadow = 0x8000;  // the user-visible TriggerSource
constexpr guint32 kRegDeviceTemperature = 0x8008;    // milli-degrees Celsius, signed
constexpr guint32 kRegBlackLevel = 0x800c;
constexpr guint32 kSourceLine1 = 2;
constexpr guint32 kSourceSoftware = 1;
constexpr guint32 kPixelMono8 = 0x01080001;
constexpr guint32 kPixelMono12 = 0x01100005;
constexpr guint32 kPixelMono16 = 0x01100007;
constexpr int kGvcpPort = 3956;
constexpr std::size_t kRecordsKept = 1000;

// True if UDP 127.0.0.1:3956 can be bound now (nobody else serves GVCP there).
bool GvcpPortFree(std::string* why) {
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  if (fd < 0) {
    *why = std::string("socket(): ") + std::strerror(errno);
    return false;
  }
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(kGvcpPort);
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  const bool ok = ::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) == 0;
  if (!ok) *why = std::strerror(errno);
  ::close(fd);
  return ok;
}

void SleepSim(const World& world, double sim_s) {
  if (sim_s <= 0.0) return;
  std::this_thread::sleep_for(world.clock().HostDuration(sim_s));
}

}  // namespace

struct CameraServer::Impl {
  Impl(World& w, const RigPhysics& p) : world(w), physics(p), renderer(p) {
    drop_rate = p.camera.drop_frame_rate;
    lost_ratio = p.camera.lost_packet_ratio;
  }

  World& world;
  RigPhysics physics;
  Renderer renderer;
  ArvGvFakeCamera* gv = nullptr;
  ArvFakeCamera* fake = nullptr;
  std::string xml_path;

  std::atomic<double> drop_rate{0.0};
  std::atomic<double> lost_ratio{0.0};
  double applied_lost_ratio = -1.0;  // camera thread only
  std::mt19937_64 fault_rng{1};      // camera thread only
  std::uint64_t frame_counter = 0;   // camera thread only

  mutable std::mutex mutex;
  std::deque<FrameRecord> records;
  std::uint64_t exposed = 0;
  std::uint64_t dropped = 0;
  std::atomic<std::uint64_t> pulses_accepted{0};
  std::mutex pulse_mutex;  // guards `fake` between the trigger line and Stop()

  guint32 Read(guint32 address) const {
    guint32 value = 0;
    if (!arv_fake_camera_read_register(fake, address, &value)) return 0;
    return value;
  }
  void Write(guint32 address, guint32 value) {
    const gboolean ok = arv_fake_camera_write_register(fake, address, value);
    IRDIST_CHECK(ok, "fake camera register write failed at 0x", std::hex, address);
  }

  void OnLinePulse() {
    std::lock_guard<std::mutex> lock(pulse_mutex);
    if (fake == nullptr) return;
    if (Read(kRegTriggerMode) == 1 && Read(kRegTriggerSourceShadow) == kSourceLine1) {
      Write(kRegTriggerSoftware, 1);
      ++pulses_accepted;
    }
  }

  void SetLostRatio(double ratio) {
    if (ratio == applied_lost_ratio) return;
    g_object_set(G_OBJECT(gv), "gvsp-lost-ratio", ratio, nullptr);
    applied_lost_ratio = ratio;
  }

  // The fake camera's fill-pattern callback: runs on its only thread, once per frame.
  void Fill(ArvBuffer* buffer, guint32 exposure_us, ArvPixelFormat pixel_format) {
    const auto host_start = std::chrono::steady_clock::now();
    const std::uint64_t index = ++frame_counter;
    const double exposure_s = exposure_us * 1e-6;
    FrameConditions c;
    const double t0 = world.clock().Now();
    c.pose_start = world.Pose();
    c.exposure_s = exposure_s;
    c.black_offset_dn = static_cast<double>(Read(kRegBlackLevel));
    // The exposure takes its (simulated) time; the world may move meanwhile.
    SleepSim(world, exposure_s);
    c.pose_end = world.Pose();
    c.junction_rise_k =
        renderer.scene().JunctionRiseK(world.CurrentHistory(), t0 + 0.5 * exposure_s);

    const bool drop = std::uniform_real_distribution<double>(0.0, 1.0)(fault_rng) < drop_rate;
    SetLostRatio(drop ? 1.0 : lost_ratio.load());

    PixelFormat format = PixelFormat::kMono8;
    switch (pixel_format) {
      case kPixelMono8:
        format = PixelFormat::kMono8;
        break;
      case kPixelMono12:
        format = PixelFormat::kMono12;
        break;
      case kPixelMono16:
        format = PixelFormat::kMono16;
        break;
      default:
        format = PixelFormat::kMono8;
        break;
    }
    const int width = static_cast<int>(arv_buffer_get_image_width(buffer));
    const int height = static_cast<int>(arv_buffer_get_image_height(buffer));
    const int x = static_cast<int>(arv_buffer_get_image_x(buffer));
    const int y = static_cast<int>(arv_buffer_get_image_y(buffer));
    // The fake camera allocates its buffer for the full payload but reports a received size of
    // 0 until filled: check against the payload it computes.
    size_t size = 0;
    void* data = const_cast<void*>(arv_buffer_get_data(buffer, &size));
    size = arv_fake_camera_get_payload(fake);
    const size_t bytes_per_pixel = format == PixelFormat::kMono8 ? 1 : 2;
    if (data != nullptr && width > 0 && height > 0 &&
        static_cast<size_t>(width) * height * bytes_per_pixel <= size) {
      cv::Mat out(height, width, FormatCvType(format), data);
      renderer.Render(c, index, format, cv::Point(x, y), out);
    }

    const guint32 temperature_mc =
        static_cast<guint32>(static_cast<gint32>(std::lround(physics.sensor.temperature_c * 1000)));
    Write(kRegDeviceTemperature, temperature_mc);

    FrameRecord record;
    record.index = index;
    record.sim_time_s = t0;
    record.exposure_us = exposure_us;
    record.slide_mm = c.pose_start.slide_mm;
    record.theta_deg = c.pose_start.ThetaDeg();
    record.bias_ma = c.pose_start.bias_ma;
    record.junction_rise_k = c.junction_rise_k;
    record.moving = c.pose_start.moving || c.pose_end.moving;
    record.dropped = drop;
    record.format = PixelFormatName(format);
    {
      std::lock_guard<std::mutex> lock(mutex);
      ++exposed;
      if (drop) ++dropped;
      records.push_back(record);
      if (records.size() > kRecordsKept) records.pop_front();
    }
    // Readout: the frame leaves the camera `readout_ms` after the exposure ends.
    const double spent_sim_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - host_start).count() *
        world.clock().time_scale();
    SleepSim(world, exposure_s + physics.camera.readout_ms * 1e-3 - spent_sim_s);
  }

  static void FillPattern(ArvBuffer* buffer, void* data, guint32 exposure_us, guint32 /*gain*/,
                          ArvPixelFormat pixel_format) {
    static_cast<Impl*>(data)->Fill(buffer, exposure_us, pixel_format);
  }
};

CameraServer::CameraServer(World& world, const RigPhysics& physics)
    : impl_(std::make_unique<Impl>(world, physics)) {
  std::string why;
  IRDIST_CHECK(physics.IsValid(&why), why);
  impl_->fault_rng.seed(physics.sensor.seed * 7919 + 17);
}

CameraServer::~CameraServer() { Stop(); }

bool CameraServer::running() const { return impl_->gv != nullptr; }
std::string CameraServer::serial() const { return impl_->physics.camera.serial; }
std::string CameraServer::device_id() const { return "Aravis-Fake-" + serial(); }

void CameraServer::Start() {
  if (impl_->gv != nullptr) return;
  std::string why;
  if (!GvcpPortFree(&why)) {
    throw CameraServerError(
        "virtual camera: UDP port 3956 on 127.0.0.1 is already in use (" + why +
        "): another GigE Vision fake camera (irdist sim, arv-fake-gv-camera-0.8 or a test) is "
        "running on this host; stop it first (only one fake camera can serve 127.0.0.1)");
  }
  // Aravis loads the GenICam XML from a file: write the compiled-in copy to a private temp file.
  char path[] = "/tmp/irdist-virtual-camera-XXXXXX.xml";
  const int fd = ::mkstemps(path, 4);
  if (fd < 0) {
    throw CameraServerError(std::string("virtual camera: cannot create a temporary file in /tmp "
                                        "for its GenICam XML: ") + std::strerror(errno));
  }
  const std::string xml(internal::kVirtualCameraXml);
  const bool written = ::write(fd, xml.data(), xml.size()) == static_cast<ssize_t>(xml.size());
  ::close(fd);
  impl_->xml_path = path;
  if (!written) {
    ::unlink(path);
    throw CameraServerError(std::string("virtual camera: cannot write ") + path);
  }

  const std::string serial = impl_->physics.camera.serial;
  ArvGvFakeCamera* gv = arv_gv_fake_camera_new_full("127.0.0.1", serial.c_str(), path);
  ::unlink(path);  // the fake camera has read it into memory
  if (gv == nullptr || !arv_gv_fake_camera_is_running(gv)) {
    if (gv != nullptr) g_object_unref(gv);
    throw CameraServerError("virtual camera: Aravis could not start a fake GigE camera on "
                            "127.0.0.1 (is the loopback interface up?)");
  }
  impl_->gv = gv;
  impl_->fake = arv_gv_fake_camera_get_fake_camera(gv);
  ArvFakeCamera* fake = impl_->fake;
  const SensorOptions& s = impl_->physics.sensor;
  impl_->Write(kRegSensorWidth, static_cast<guint32>(s.width_px));
  impl_->Write(kRegSensorHeight, static_cast<guint32>(s.height_px));
  impl_->Write(kRegWidth, static_cast<guint32>(s.width_px));
  impl_->Write(kRegHeight, static_cast<guint32>(s.height_px));
  impl_->Write(kRegTriggerSource, kSourceSoftware);
  impl_->Write(kRegTriggerSourceShadow, kSourceLine1);
  impl_->Write(kRegBlackLevel, 0);
  impl_->Write(kRegDeviceTemperature,
               static_cast<guint32>(static_cast<gint32>(std::lround(s.temperature_c * 1000))));
  arv_fake_camera_set_trigger_frequency(fake, impl_->physics.camera.trigger_frequency_hz);
  arv_fake_camera_set_fill_pattern(fake, &Impl::FillPattern, impl_.get());
  Impl* impl = impl_.get();
  impl_->world.SetTriggerSink([impl] { impl->OnLinePulse(); });
}

void CameraServer::Stop() {
  if (impl_->gv == nullptr) return;
  impl_->world.SetTriggerSink(nullptr);
  ArvGvFakeCamera* gv = impl_->gv;
  {
    std::lock_guard<std::mutex> lock(impl_->pulse_mutex);
    impl_->gv = nullptr;
    impl_->fake = nullptr;
  }
  g_object_unref(gv);  // joins the camera thread and closes its sockets
}

void CameraServer::SetDropFrameRate(double rate) {
  IRDIST_CHECK(rate >= 0.0 && rate <= 1.0, "drop rate must lie in [0, 1]");
  impl_->drop_rate = rate;
}

void CameraServer::SetLostPacketRatio(double ratio) {
  IRDIST_CHECK(ratio >= 0.0 && ratio <= 1.0, "lost packet ratio must lie in [0, 1]");
  impl_->lost_ratio = ratio;
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

}  // namespace irdist::sim
