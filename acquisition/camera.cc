#include "acquisition/camera.h"

#include "acquisition/pixel_format.h"

namespace irdist {

bool CameraSettings::IsValid(std::string* why) const {
  auto fail = [why](const std::string& message) {
    if (why != nullptr) *why = message;
    return false;
  };
  if (FindPixelFormat(pixel_format) == nullptr) {
    return fail("pixel_format must be one of " + SupportedPixelFormatNames() + ", got '" +
                pixel_format + "'");
  }
  if (triggered && trigger_source.empty()) return fail("trigger_source is empty");
  if (width < 0 || height < 0 || offset_x < 0 || offset_y < 0) {
    return fail("width, height and offsets must be >= 0 (0 = full sensor)");
  }
  if (frame_rate_hz < 0.0) return fail("frame_rate_hz must be >= 0 (0 = leave as is)");
  if (!(exposure_us > 0.0)) return fail("exposure_us must be > 0");
  if (packet_size < 0) return fail("packet_size must be >= 0 (0 = negotiate)");
  if (socket_buffer_bytes < 0) return fail("socket_buffer_bytes must be >= 0 (0 = from payload)");
  if (buffer_count < 2) return fail("buffer_count must be >= 2");
  if (warmup_frames < 0) return fail("warmup_frames must be >= 0");
  if (frame_retention_ms < 1) return fail("frame_retention_ms must be >= 1");
  if (!(packet_request_ratio > 0.0 && packet_request_ratio <= 2.0)) {
    return fail("packet_request_ratio must be in (0, 2]");
  }
  if (!(readback_tolerance >= 0.0 && readback_tolerance < 0.5)) {
    return fail("readback_tolerance must be in [0, 0.5)");
  }
  return true;
}

const char* ExposureCheckName(ExposureCheck check) {
  switch (check) {
    case ExposureCheck::kAuto:
      return "auto";
    case ExposureCheck::kChunk:
      return "chunk";
    case ExposureCheck::kReadback:
      return "readback";
    case ExposureCheck::kNone:
      return "none";
  }
  return "auto";
}

std::optional<ExposureCheck> ParseExposureCheck(const std::string& name) {
  for (ExposureCheck check : {ExposureCheck::kAuto, ExposureCheck::kChunk,
                              ExposureCheck::kReadback, ExposureCheck::kNone}) {
    if (name == ExposureCheckName(check)) return check;
  }
  return std::nullopt;
}

const char* FrameStatusName(FrameStatus status) {
  switch (status) {
    case FrameStatus::kOk:
      return "ok";
    case FrameStatus::kTimeout:
      return "timeout";
    case FrameStatus::kMissingPackets:
      return "missing_packets";
    case FrameStatus::kWrongPacketId:
      return "wrong_packet_id";
    case FrameStatus::kSizeMismatch:
      return "size_mismatch";
    case FrameStatus::kAborted:
      return "aborted";
    case FrameStatus::kUnderrun:
      return "underrun";
    case FrameStatus::kFilling:
      return "filling";
    case FrameStatus::kWrongExposure:
      return "wrong_exposure";
    case FrameStatus::kUnknown:
      return "unknown";
  }
  return "unknown";
}

}  // namespace irdist
