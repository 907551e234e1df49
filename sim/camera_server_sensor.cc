// The virtual camera's sensor (sim/camera_server_impl.h): a frame starts at a trigger or the
// free-running period, latches its settings, exposes the World's scene (rendered), reads out, is
// sent, and is kept for resend requests.
#include <arpa/inet.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <mutex>
#include <random>

#include "sim/camera_server_impl.h"

namespace irdist::sim {
namespace {

constexpr std::size_t kRecordsKept = 1000;
constexpr std::size_t kFramesKeptForResend = 8;

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

}  // namespace

FrameSetup CameraServer::Impl::LatchSetup() {
  std::lock_guard<std::mutex> lock(reg_mutex);
  return LatchSetupLocked();
}

FrameSetup CameraServer::Impl::LatchSetupLocked() const {
  FrameSetup s;
  s.exposure_us = static_cast<double>(ReadLocked(kRegExposureUs));
  s.pixel_format = ReadLocked(kRegPixelFormat);
  s.width = static_cast<int>(ReadLocked(kRegWidth));
  s.height = static_cast<int>(ReadLocked(kRegHeight));
  s.offset_x = static_cast<int>(ReadLocked(kRegOffsetX));
  s.offset_y = static_cast<int>(ReadLocked(kRegOffsetY));
  s.black_offset_dn = static_cast<double>(ReadLocked(kRegBlackLevel));
  s.curve_gamma = physics.camera.fixed_gamma *
                  (ReadLocked(kRegLutEnable) != 0 ? physics.camera.lut_gamma : 1.0);
  s.chunks = ReadLocked(kRegChunkModeActive) != 0;
  s.exposure_chunk = s.chunks && ReadLocked(kRegChunkEnableExposure) != 0;
  s.packet_size = std::max<guint32>(ReadLocked(kRegPacketSize) & 0xffff, 576);
  s.destination.sin_family = AF_INET;
  s.destination.sin_addr.s_addr = htonl(ReadLocked(kRegStreamAddress));
  s.destination.sin_port = htons(static_cast<std::uint16_t>(ReadLocked(kRegStreamPort) & 0xffff));
  return s;
}

void CameraServer::Impl::SleepSim(double sim_s) {
  if (sim_s <= 0.0) return;
  std::unique_lock<std::mutex> lock(state_mutex);
  wake.wait_for(lock, world.clock().HostDuration(sim_s), [this] { return stopping; });
}

FrameRecord CameraServer::Impl::Expose(const FrameSetup& s, std::uint64_t index,
                                       std::vector<std::uint8_t>& payload) {
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
    ApplyResponseCurve(s.curve_gamma, format, out);
    payload.assign((pixels * 12 + 7) / 8, 0);
    if (pixels > 0) PackMono12p(out, payload.data());
  } else {
    const std::size_t bytes_per_pixel = format == PixelFormat::kMono8 ? 1 : 2;
    payload.assign(pixels * bytes_per_pixel, 0);
    if (pixels > 0) {
      cv::Mat out(s.height, s.width, FormatCvType(format), payload.data());
      renderer.Render(c, index, format, cv::Point(s.offset_x, s.offset_y), out);
      ApplyResponseCurve(s.curve_gamma, format, out);
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

void CameraServer::Impl::RunFrame(const std::optional<FrameSetup>& latched) {
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
  if (s.chunks) {
    // The exposure chunk fault: the camera still declares and enables it, the frame lacks it.
    const std::uint64_t drop_from =
        static_cast<std::uint64_t>(physics.camera.drop_exposure_chunks_from_frame);
    FrameSetup with_chunks = s;
    with_chunks.exposure_chunk = s.exposure_chunk && !(drop_from > 0 && index >= drop_from);
    AppendChunks(with_chunks, payload);
  }
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

void CameraServer::Impl::Keep(FrameRecord record, std::shared_ptr<const SentFrame> frame) {
  std::lock_guard<std::mutex> lock(mutex);
  ++exposed;
  if (record.dropped) ++dropped;
  records.push_back(std::move(record));
  if (records.size() > kRecordsKept) records.pop_front();
  if (frame != nullptr) sent.push_back(std::move(frame));
  if (sent.size() > kFramesKeptForResend) sent.pop_front();
}

bool CameraServer::Impl::WaitForFrameStart(SteadyClock::time_point* next_free_run,
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

void CameraServer::Impl::SensorLoop() {
  auto next_free_run = SteadyClock::now();
  std::optional<FrameSetup> latched;
  while (WaitForFrameStart(&next_free_run, &latched)) {
    RunFrame(latched);
    std::lock_guard<std::mutex> lock(state_mutex);
    busy = false;
  }
}

}  // namespace irdist::sim
