// AravisCamera's stream: GigE Vision packets and resend, the stream's buffers, frames taken from
// it (the grabber's hot path: bench/acquisition measures it).
#include <algorithm>
#include <cmath>

#include "acquisition/aravis_internal.h"
#include "acquisition/pixel_format.h"
#include "base/utc_time.h"

namespace irdist {
namespace {

FrameStatus MapStatus(ArvBufferStatus status) {
  switch (status) {
    case ARV_BUFFER_STATUS_SUCCESS:
      return FrameStatus::kOk;
    case ARV_BUFFER_STATUS_TIMEOUT:
      return FrameStatus::kTimeout;
    case ARV_BUFFER_STATUS_MISSING_PACKETS:
      return FrameStatus::kMissingPackets;
    case ARV_BUFFER_STATUS_WRONG_PACKET_ID:
      return FrameStatus::kWrongPacketId;
    case ARV_BUFFER_STATUS_SIZE_MISMATCH:
      return FrameStatus::kSizeMismatch;
    case ARV_BUFFER_STATUS_FILLING:
      return FrameStatus::kFilling;
    case ARV_BUFFER_STATUS_ABORTED:
      return FrameStatus::kAborted;
    case ARV_BUFFER_STATUS_CLEARED:
      return FrameStatus::kUnknown;
    case ARV_BUFFER_STATUS_UNKNOWN:
      return FrameStatus::kUnknown;
  }
  return FrameStatus::kUnknown;
}

}  // namespace

bool IsLoopback(const std::string& address) { return address.rfind("127.", 0) == 0; }

// GigE Vision: packet socket off on loopback, the rig's packet size or a negotiated one.
void AravisCamera::Impl::SetupPacketSize() {
  if (arv_camera_is_gv_device(camera.get()) == FALSE) return;
  GError* error = nullptr;
  arv_camera_gv_set_stream_options(camera.get(),
                                   IsLoopback(identity.address)
                                       ? ARV_GV_STREAM_OPTION_PACKET_SOCKET_DISABLED
                                       : ARV_GV_STREAM_OPTION_NONE);
  if (settings.packet_size > 0) {
    arv_camera_gv_set_packet_size(camera.get(), settings.packet_size, &error);
    ThrowOnError(error, "setting the packet size", Name());
    const guint back = arv_camera_gv_get_packet_size(camera.get(), &error);
    ThrowOnError(error, "reading the packet size", Name());
    if (static_cast<int>(back) != settings.packet_size) {
      throw CameraError("camera " + Name() + ": packet size " +
                        std::to_string(settings.packet_size) + " reads back " +
                        std::to_string(back) +
                        "; use a packet size the network path supports or 0 to negotiate.");
    }
    packet_size = static_cast<int>(back);
  } else {
    packet_size = static_cast<int>(arv_camera_gv_auto_packet_size(camera.get(), &error));
    ThrowOnError(error, "negotiating the packet size", Name());
  }
}

// GigE Vision stream: fixed socket buffer, packet resend when the camera supports it (GVCP
// capability bit), the frame retention.
void AravisCamera::Impl::TuneGvStream(ArvStream* raw_stream) {
  if (!ARV_IS_GV_STREAM(raw_stream)) return;
  const int socket_bytes = settings.socket_buffer_bytes > 0
                               ? settings.socket_buffer_bytes
                               : std::max(4 << 20, 2 * payload_bytes);
  const bool resend = DeclaresResend();
  g_object_set(raw_stream, "socket-buffer", ARV_GV_STREAM_SOCKET_BUFFER_FIXED,
               "socket-buffer-size", socket_bytes, "packet-resend",
               resend ? ARV_GV_STREAM_PACKET_RESEND_ALWAYS : ARV_GV_STREAM_PACKET_RESEND_NEVER,
               "frame-retention", static_cast<guint>(settings.frame_retention_ms * 1000),
               "packet-request-ratio", settings.packet_request_ratio, nullptr);
  gint size_back = 0;
  guint retention_back = 0;
  double ratio_back = 0.0;
  g_object_get(raw_stream, "socket-buffer-size", &size_back, "frame-retention",
               &retention_back, "packet-request-ratio", &ratio_back, nullptr);
  if (size_back != socket_bytes ||
      retention_back != static_cast<guint>(settings.frame_retention_ms * 1000) ||
      std::fabs(ratio_back - settings.packet_request_ratio) > 1e-9) {
    throw CameraError("camera " + Name() +
                      ": the stream did not keep its socket buffer / frame retention / packet "
                      "request ratio settings; this Aravis version is not supported (need 0.8.x).");
  }
}

// The GVCP capability register's PACKETRESEND_CMD bit (GigE Vision devices only).
bool AravisCamera::Impl::DeclaresResend() {
  if (arv_camera_is_gv_device(camera.get()) == FALSE) return false;
  GError* error = nullptr;
  guint32 capabilities = 0;
  arv_device_read_register(Device(), 0x0934, &capabilities, &error);
  ThrowOnError(error, "reading the GVCP capability register", Name());
  return (capabilities & (1u << 2)) != 0;
}

void AravisCamera::Impl::SetupStream() {
  GError* error = nullptr;
  stream.reset();
  SetupPacketSize();
  payload_bytes = static_cast<int>(arv_camera_get_payload(camera.get(), &error));
  ThrowOnError(error, "reading PayloadSize", Name());
  if (payload_bytes <= 0) {
    throw CameraError("camera " + Name() + " reports a payload of " +
                      std::to_string(payload_bytes) + " bytes; check Width/Height/PixelFormat.");
  }

  ArvStream* raw_stream = arv_camera_create_stream(camera.get(), nullptr, nullptr, &error);
  ThrowOnError(error, "creating the stream", Name());
  if (raw_stream == nullptr) {
    throw CameraError("camera " + Name() + ": Aravis could not create a stream; check the " +
                      "network interface and firewall (UDP from the camera).");
  }
  stream.reset(raw_stream);

  TuneGvStream(raw_stream);
  for (int i = 0; i < settings.buffer_count; ++i) {
    arv_stream_push_buffer(raw_stream, arv_buffer_new_allocate(payload_bytes));
  }
}

// The frame's image as CV_16UC1 (packed formats unpacked), or empty when the buffer does not
// hold a whole image of a supported format.
cv::Mat AravisCamera::Impl::ToMat(ArvBuffer* buffer) {
  const int width = arv_buffer_get_image_width(buffer);
  const int height = arv_buffer_get_image_height(buffer);
  size_t size = 0;
  const void* data = arv_buffer_get_image_data(buffer, &size);
  const PixelFormatInfo* format =
      FindPixelFormat(static_cast<std::uint32_t>(arv_buffer_get_image_pixel_format(buffer)));
  if (format == nullptr) return cv::Mat();
  return UnpackMono(*format, static_cast<const std::uint8_t*>(data), size, width, height);
}

void AravisCamera::StartStream() {
  Impl& d = *impl_;
  IRDIST_CHECK(d.configured && d.stream != nullptr, "StartStream() before Configure()");
  if (d.streaming) return;
  GError* error = nullptr;
  arv_camera_start_acquisition(d.camera.get(), &error);
  ThrowOnError(error, "starting acquisition", d.Name());
  d.streaming = true;
  const bool self_timed = !d.settings.triggered || d.settings.trigger_source == "Software";
  for (int i = 0; self_timed && i < d.settings.warmup_frames; ++i) {
    if (d.settings.triggered) SoftwareTrigger();
    const auto frame = WaitFrame(std::chrono::milliseconds(2000));
    if (!frame) break;  // nothing to warm up with; the capture's retries take over
    ++d.warmup_discarded;
  }
}

int AravisCamera::warmup_discarded() const { return impl_->warmup_discarded; }

void AravisCamera::StopStream() {
  Impl& d = *impl_;
  if (!d.streaming) return;
  d.streaming = false;
  GError* error = nullptr;
  arv_camera_stop_acquisition(d.camera.get(), &error);
  ThrowOnError(error, "stopping acquisition", d.Name());
}

bool AravisCamera::streaming() const { return impl_->streaming; }

std::optional<RawFrame> AravisCamera::WaitFrame(std::chrono::milliseconds timeout) {
  Impl& d = *impl_;
  IRDIST_CHECK(d.stream != nullptr, "WaitFrame() before Configure()");
  const auto timeout_us = static_cast<guint64>(std::max<std::int64_t>(0, timeout.count()) * 1000);
  ArvBuffer* buffer = arv_stream_timeout_pop_buffer(d.stream.get(), timeout_us);
  if (buffer == nullptr) return std::nullopt;
  RawFrame frame;
  // Received: stamped the moment the complete frame is taken from the stream, before any copy.
  frame.host_time_ns = UtcNowNs();
  frame.host_monotonic_ns = MonotonicNowNs();
  frame.status = MapStatus(arv_buffer_get_status(buffer));
  frame.frame_id = arv_buffer_get_frame_id(buffer);
  frame.timestamp_ns = arv_buffer_get_timestamp(buffer);
  frame.bit_depth = d.bit_depth;
  if (frame.status == FrameStatus::kOk) {
    frame.image = d.ToMat(buffer);
    if (frame.image.empty()) frame.status = FrameStatus::kSizeMismatch;
    if (d.exposure_chunks && arv_buffer_has_chunks(buffer) != FALSE) {
      GError* error = nullptr;
      const double chunk = arv_chunk_parser_get_float_value(d.chunk_parser.get(), buffer,
                                                            "ChunkExposureTime", &error);
      if (error == nullptr) {
        frame.chunk_exposure_us = chunk;
      } else {
        g_error_free(error);  // a frame without a readable chunk falls back to the read-back
      }
    }
  }
  arv_stream_push_buffer(d.stream.get(), buffer);
  return frame;
}

int AravisCamera::Flush() {
  Impl& d = *impl_;
  if (d.stream == nullptr) return 0;
  int count = 0;
  while (ArvBuffer* buffer = arv_stream_try_pop_buffer(d.stream.get())) {
    arv_stream_push_buffer(d.stream.get(), buffer);
    ++count;
  }
  return count;
}

void AravisCamera::SoftwareTrigger() {
  GError* error = nullptr;
  arv_camera_software_trigger(impl_->camera.get(), &error);
  ThrowOnError(error, "TriggerSoftware", impl_->Name());
}

bool AravisCamera::HasExposureChunks() const { return impl_->exposure_chunks; }

ExposureCheck AravisCamera::exposure_check() const { return impl_->settings.exposure_check; }

std::map<std::string, std::uint64_t> AravisCamera::StreamStatistics() const {
  std::map<std::string, std::uint64_t> out;
  if (impl_->stream == nullptr) return out;
  ArvStream* stream = impl_->stream.get();
  const guint count = arv_stream_get_n_infos(stream);
  for (guint i = 0; i < count; ++i) {
    if (arv_stream_get_info_type(stream, i) == G_TYPE_UINT64) {
      out[OrEmpty(arv_stream_get_info_name(stream, i))] = arv_stream_get_info_uint64(stream, i);
    }
  }
  return out;
}

TransferStats AravisCamera::Transfer() const {
  TransferStats out;
  if (impl_->stream == nullptr || !ARV_IS_GV_STREAM(impl_->stream.get())) return out;
  const std::map<std::string, std::uint64_t> infos = StreamStatistics();
  auto get = [&infos](const char* name) {
    const auto it = infos.find(name);
    return it == infos.end() ? std::uint64_t{0} : it->second;
  };
  out.resend_requests = get("n_resend_requests");
  out.resent_packets = get("n_resent_packets");
  out.missing_packets = get("n_missing_packets");
  out.completed_frames = get("n_completed_buffers");
  out.failed_frames = get("n_failures");
  return out;
}

bool AravisCamera::DeclaresPacketResend() { return impl_->DeclaresResend(); }

int AravisCamera::PayloadBytes() const { return impl_->payload_bytes; }
int AravisCamera::PacketSizeBytes() const { return impl_->packet_size; }

}  // namespace irdist
