#pragma once
// The camera seen by the rest of irdist: an interface (so tests and app/ can substitute their own)
// with its settings, identity and per-frame outcome types. The Aravis implementation lives in
// acquisition/aravis_camera.h; nothing here carries a GLib or Aravis type.

#include <chrono>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "base/check.h"

namespace irdist {

// A camera (device) failure: missing or clamped feature, wrong serial, dead link, Aravis error.
// The message says what, on which camera, and what to do.
class CameraError : public Error {
 public:
  using Error::Error;
};

// What one camera is, as read from it (goes into recording.yaml).
struct CameraIdentity {
  std::string vendor;
  std::string model;
  std::string serial;
  std::string firmware;
  std::string address;  // IP address for GigE Vision cameras
  std::string BriefReport() const;
};

// One camera found by discovery (`irdist devices`).
struct DeviceInfo {
  std::string id;        // Aravis device id, e.g. "Aravis-Fake-GV01"
  std::string vendor;
  std::string model;
  std::string serial;
  std::string address;   // IP address (GigE) or empty
  std::string protocol;  // "GigEVision", "USB3Vision", ...
};

// What each frame's exposure is checked against (the rig file's camera.exposure_check;
// docs/recipes.md "The camera's state").
enum class ExposureCheck {
  // The default: the frame's own ChunkExposureTime where the camera declares it and its frames
  // carry it; once a frame comes without it (never sent, or stopped), the read-back, said once.
  kAuto,
  kChunk,     // the chunk only: a camera without it is refused, a frame without it is rejected
  kReadback,  // chunks off: each exposure written and read back before its trigger
  kNone,      // written, neither read back nor checked (a camera whose read-back cannot be trusted)
};
const char* ExposureCheckName(ExposureCheck check);  // "auto", "chunk", "readback", "none"
// The rig file's spelling ("chunk", "readback", "none"; "auto" the default) or std::nullopt.
std::optional<ExposureCheck> ParseExposureCheck(const std::string& name);

// How to configure a camera for irdist (from the rig file's camera: section).
struct CameraSettings {
  // GenICam PixelFormat: Mono8, Mono10, Mono10p, Mono12, Mono12p, Mono12Packed, Mono14 or Mono16
  // (acquisition/pixel_format.h). Frames are always delivered as CV_16UC1 with the values the
  // camera sent (packed formats unpacked, never rescaled).
  std::string pixel_format = "Mono12";
  // FrameStart trigger source: "Line1" (wired to the station) or "Software" (tests).
  std::string trigger_source = "Line1";
  // TriggerActivation for hardware lines ("RisingEdge", "FallingEdge"); ignored for Software.
  std::string trigger_activation = "RisingEdge";
  // Trigger mode on (the normal case); off = free-running at the camera's frame rate.
  bool triggered = true;
  // Free-running frame rate (AcquisitionFrameRate) when triggered == false; 0 = leave as is.
  double frame_rate_hz = 0.0;
  // BlackLevel in the camera's units; negative = leave as is. Skipped if the camera has none.
  double black_level = 0.0;
  // Gamma; <= 0 = leave as is. Only set where the camera has a Gamma feature.
  double gamma = 1.0;
  // Region of interest; 0 = the camera's maximum (width/height) or 0 (offsets).
  int width = 0;
  int height = 0;
  int offset_x = 0;
  int offset_y = 0;
  // Initial exposure (us) set while configuring.
  double exposure_us = 10000.0;
  // GigE Vision stream packet size in bytes; 0 = negotiate with the camera.
  int packet_size = 0;
  // Kernel socket buffer for the stream (bytes); 0 = sized from the payload (min 4 MB).
  int socket_buffer_bytes = 0;
  // Number of frame buffers queued on the stream (at least the longest bracket + 2).
  int buffer_count = 16;
  // How long a partially received frame is kept before it is given up (ms). Low values detect a
  // lost triggered frame quickly (it comes back as a timeout).
  int frame_retention_ms = 50;
  // Frames discarded right after AcquisitionStart in free-run and Software-trigger modes: Aravis
  // sizes the stream's socket buffer on the first packet, so the first frame may come incomplete.
  // (With a hardware trigger, BracketOptions::warmup_trigger does the same through the trigger.)
  int warmup_frames = 1;
  // The rig's camera.trigger_in_readout: where the camera has TriggerOverlap, it is set to
  // ReadOut (a camera without the feature is taken to accept such a trigger as documented).
  bool trigger_in_readout = false;
  // GigE Vision packet resend: the most resend requests per frame, as a fraction of its packets
  // (Aravis's packet-request-ratio). 1.0 lets a frame with many lost packets be completed.
  double packet_request_ratio = 1.0;
  // Ask for ChunkExposureTime when the camera offers it (each frame then says the exposure it was
  // taken with, which lets BracketCapture pipeline its exposure writes); false = chunks off.
  bool exposure_chunks = true;
  // How a frame's exposure is verified (above). kReadback and kNone turn chunks off; kChunk
  // refuses a camera that does not declare ChunkExposureTime.
  ExposureCheck exposure_check = ExposureCheck::kAuto;
  // For the command that owns the camera (the rig's camera.restore_after): put back what
  // Configure changed when it is done with the camera, however it ends. Configure ignores it.
  bool restore_after = true;
  // Relative tolerance when a value read back must equal the value set (floats only).
  double readback_tolerance = 0.005;
  bool IsValid(std::string* why) const;
};

// The outcome of one frame, as the grabber saw it. Expected failures are values, not exceptions.
enum class FrameStatus {
  kOk,
  kTimeout,         // nothing (complete) arrived in time
  kMissingPackets,  // incomplete frame
  kWrongPacketId,
  kSizeMismatch,
  kAborted,
  kUnderrun,        // the stream had no free buffer
  kFilling,
  kWrongExposure,   // delivered, but taken with another exposure than requested
  kUnknown,         // Aravis reported ARV_BUFFER_STATUS_UNKNOWN (-1) or an unlisted status
};
const char* FrameStatusName(FrameStatus status);

// GigE Vision transfer counters of a camera's stream since it was configured.
struct TransferStats {
  std::uint64_t resend_requests = 0;  // packets the grabber asked the camera to send again
  std::uint64_t resent_packets = 0;   // of which received
  std::uint64_t missing_packets = 0;  // packets still missing when their frame was given up
  std::uint64_t completed_frames = 0;
  std::uint64_t failed_frames = 0;
};

// One frame as it left the camera.
struct RawFrame {
  FrameStatus status = FrameStatus::kUnknown;
  cv::Mat image;                  // CV_16UC1 when status == kOk, else empty
  int bit_depth = 16;             // significant bits of the pixel values
  std::uint64_t frame_id = 0;     // camera block id (16-bit on GigE Vision 1.x, wraps)
  std::uint64_t timestamp_ns = 0; // camera timestamp (Aravis's buffer timestamp); 0 = none
  // Host wall clock (ns since the Unix epoch) when the frame was received: stamped by the grabber
  // as it takes the complete frame from the stream (before copying it), not later by its user.
  std::int64_t host_time_ns = 0;
  std::int64_t host_monotonic_ns = 0;  // the host's monotonic clock at the same moment
  std::optional<double> chunk_exposure_us;  // ChunkExposureTime when the camera sends chunks
};

class Camera {
 public:
  virtual ~Camera() = default;

  virtual CameraIdentity Identity() const = 0;
  // Applies every setting, reading back each value; throws CameraError when the camera lacks a
  // required feature or does not keep a value (clamping).
  virtual void Configure(const CameraSettings& settings) = 0;
  // Every feature value irdist relies on, read back from the camera (for recording.yaml).
  virtual std::map<std::string, std::string> ReadBackFeatures() = 0;

  // Writes the exposure and returns the value read back (us). Throws CameraError when the camera
  // clamps it beyond the settings' tolerance.
  virtual double SetExposureUs(double exposure_us) = 0;
  virtual double ExposureUs() = 0;
  // Writes the exposure without reading it back (one control round trip): for programming the
  // next frame while the current one is read out. Throws CameraError for a value outside the
  // camera's range. The default writes with SetExposureUs.
  virtual void WriteExposureUs(double exposure_us) { SetExposureUs(exposure_us); }

  // Starts streaming (AcquisitionStart) with the stream's buffers queued, then discards the
  // settings' warm-up frames where the camera can produce them by itself; StopStream ends it.
  virtual void StartStream() = 0;
  virtual void StopStream() = 0;
  virtual bool streaming() const = 0;
  // Next frame from the stream, or std::nullopt when none arrived within `timeout`. Frames whose
  // transfer failed are returned with their status and no image.
  virtual std::optional<RawFrame> WaitFrame(std::chrono::milliseconds timeout) = 0;
  // Drops every frame already queued; returns how many.
  virtual int Flush() = 0;
  // TriggerSoftware command (works when the trigger source is Software).
  virtual void SoftwareTrigger() = 0;
  // Whether frames carry ChunkExposureTime.
  virtual bool HasExposureChunks() const = 0;
  // The exposure check the camera was configured with (CameraSettings::exposure_check).
  virtual ExposureCheck exposure_check() const { return ExposureCheck::kAuto; }
  // Packet resend and loss counters (zeros for cameras without a packet transport).
  virtual TransferStats Transfer() const { return {}; }
};

}  // namespace irdist
