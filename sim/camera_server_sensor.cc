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
// A moving exposure is rendered in one sub-step per this much travel (at least 2, at most 8):
// each costs about 1.4 ms of a 256 x 256 frame's 5 ms, and the frame must be ready within its
// readout (12 ms) to keep the camera's rate.
constexpr double kSubStepMm = 2.0;
constexpr double kSubStepDeg = 0.2;
constexpr double kMaxSubSteps = 8.0;

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

// The conditions of the exposure [t0_s, t0_s + exposure_s], known once it ended: from the
// station's exact trajectory, a moving exposure in sub-steps; without one (no station profile),
// the World's pose sampled at its start (`sampled_start`) and now, at its end.
FrameConditions CameraServer::Impl::ExposureConditions(double t0_s, double exposure_s,
                                                       const PoseState& sampled_start) const {
  FrameConditions c;
  c.exposure_s = exposure_s;
  if (!world.TruthAt(t0_s).known) {
    c.pose_start = sampled_start;
    c.pose_end = world.Pose();
    return c;
  }
  c.pose_start = world.PoseAt(t0_s);
  c.pose_start.moving = sampled_start.moving;  // PoseAt's flag is now's: settling counts too
  c.pose_end = world.PoseAt(t0_s + exposure_s);
  const PoseState mid = world.PoseAt(t0_s + 0.5 * exposure_s);
  const auto travel = [&](double PoseState::*axis, double step) {
    return (std::fabs(mid.*axis - c.pose_start.*axis) + std::fabs(c.pose_end.*axis - mid.*axis)) /
           step;
  };
  const double steps = travel(&PoseState::slide_mm, kSubStepMm) +
                       travel(&PoseState::pan_deg, kSubStepDeg) +
                       travel(&PoseState::tilt_deg, kSubStepDeg);
  if (steps <= 0.0) return c;  // at rest: one pose
  const int n = static_cast<int>(std::clamp(std::ceil(steps) + 1.0, 2.0, kMaxSubSteps));
  for (int k = 0; k < n; ++k) {
    c.sub_steps.push_back(world.PoseAt(t0_s + (k + 0.5) / n * exposure_s));
  }
  return c;
}

// The frame's truth: the pose at the middle of its exposure, from the trajectory when known.
void CameraServer::Impl::RecordTruth(const FrameConditions& c, double t0_s,
                                     FrameRecord* record) const {
  record->sim_time_s = t0_s;
  record->timestamp_ns = SimTimeToNs(t0_s);
  const TrajectoryPoint mid = world.TruthAt(t0_s + 0.5 * c.exposure_s);
  record->truth_from_trajectory = mid.known;
  const PoseState& pose = c.pose_start;  // without a trajectory: the start, as sampled
  record->slide_mm = mid.known ? mid.slide_mm : pose.slide_mm;
  record->pan_deg = mid.known ? mid.pan_deg : pose.pan_deg;
  record->tilt_deg = mid.known ? mid.tilt_deg : pose.tilt_deg;
  record->theta_deg = mid.known ? mid.theta_deg : pose.ThetaDeg();
  record->slide_mm_s = mid.slide_mm_s;
  record->pan_deg_s = mid.pan_deg_s;
  record->tilt_deg_s = mid.tilt_deg_s;
  record->bias_ma = pose.bias_ma;
  record->junction_rise_k = c.junction_rise_k;
  record->moving = c.pose_start.moving || c.pose_end.moving || !c.sub_steps.empty();
}

FrameRecord CameraServer::Impl::Expose(const FrameSetup& s, std::uint64_t index,
                                       std::vector<std::uint8_t>& payload) {
  const PixelFormat format = FormatOf(s.pixel_format);
  const double exposure_s = s.exposure_us * 1e-6;
  const double t0 = world.clock().Now();
  const PoseState sampled_start = world.Pose();
  SleepSim(exposure_s);
  FrameConditions c = ExposureConditions(t0, exposure_s, sampled_start);
  c.black_offset_dn = s.black_offset_dn;
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
  record.exposure_us = s.exposure_us;
  RecordTruth(c, t0, &record);
  record.format = s.pixel_format == kPixelMono12p ? "Mono12p" : PixelFormatName(format);
  return record;
}

void CameraServer::Impl::RunFrame(const std::optional<FrameSetup>& latched) {
  const auto host_start = SteadyClock::now();
  const FrameSetup s = latched.has_value() ? *latched : LatchSetup();
  const std::uint64_t index = ++frame_counter;
  const std::uint16_t block_id = next_block_id;
  next_block_id = static_cast<std::uint16_t>(next_block_id == 0xffff ? 1 : next_block_id + 1);
  std::vector<std::uint8_t> payload;
  FrameRecord record = Expose(s, index, payload);
  record.block_id = block_id;
  const std::uint64_t timestamp_ns = record.timestamp_ns;  // the exposure's start, world's clock
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
