// The virtual camera as a device (sim/camera_server.h, sim/camera_server_impl.h): start and stop
// (sockets, threads, the GenICam register map), the registers' power-up values, the triggers
// (Line1 pulses and TriggerSoftware), the fault knobs and the observation of what it did.
#include <arpa/inet.h>
#include <arv.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <mutex>
#include <thread>

#include "sim/camera_server_impl.h"

namespace irdist::sim {
namespace internal {
extern const char* const kVirtualCameraXml;
}  // namespace internal

namespace {

constexpr guint32 kCapabilityWriteMemory = 1u << 1;  // bit numbering as Aravis reads it
constexpr guint32 kCapabilityPacketResend = 1u << 2;
constexpr int kGvcpPort = 3956;
constexpr int kTriggerQueue = 4;

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

}  // namespace

guint32 CameraServer::Impl::ReadLocked(guint32 address) const {
  guint32 value = 0;
  if (fake == nullptr || !arv_fake_camera_read_register(fake, address, &value)) return 0;
  return value;
}

void CameraServer::Impl::WriteLocked(guint32 address, guint32 value) {
  if (fake != nullptr) arv_fake_camera_write_register(fake, address, value);
}

guint32 CameraServer::Impl::Read(guint32 address) const {
  std::lock_guard<std::mutex> lock(reg_mutex);
  return ReadLocked(address);
}

void CameraServer::Impl::Write(guint32 address, guint32 value) {
  std::lock_guard<std::mutex> lock(reg_mutex);
  WriteLocked(address, value);
}

void CameraServer::Impl::InitRegisters() {
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
  WriteLocked(kRegLutEnable, physics.camera.lut_enable ? 1 : 0);
  WriteLocked(kRegGvcpCapability,
              kCapabilityWriteMemory | (packet_resend ? kCapabilityPacketResend : 0u));
  WriteLocked(kRegDeviceTemperature,
              static_cast<guint32>(static_cast<gint32>(std::lround(s.temperature_c * 1000))));
}

bool CameraServer::Impl::OfferTrigger(guint32 source) {
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

void CameraServer::Impl::OnLinePulse() {
  if (OfferTrigger(kSourceLine1)) ++pulses_accepted;
}

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
