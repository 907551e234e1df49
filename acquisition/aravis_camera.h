#pragma once
// The Aravis (GenICam / GigE Vision) implementation of Camera. The only client code in irdist that
// includes <arv.h> is in its parts (aravis_internal.h lists them); this header carries no GLib or
// Aravis type.

#include <chrono>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "acquisition/camera.h"
#include "acquisition/pixel_pipeline.h"

namespace irdist {

// Cameras visible to Aravis now (GigE Vision discovery, USB3 Vision, Aravis's fake interface).
// GigE Vision discovery broadcasts on every network interface: call it only when the user asks
// (`irdist devices --discover`, or opening a camera by id or serial), never from tests.
std::vector<DeviceInfo> ListCameras();

// The device that `id_serial_or_ip` names among `devices` (matched by Aravis id or serial number).
// Throws CameraError listing the cameras found when none matches.
DeviceInfo ResolveCamera(const std::string& id_serial_or_ip, const std::vector<DeviceInfo>& devices);

// One GenICam feature as a camera describes it now (for `irdist camera-test`).
struct FeatureInfo {
  bool present = false;               // implemented and available now
  bool writable = false;
  std::string value;                  // as a string; empty when unreadable
  std::vector<std::string> entries;   // an enumeration's available entries
  std::optional<double> min, max;     // a number's bounds, when it has them
};

class AravisCamera final : public Camera {
 public:
  // Opens the camera named by `id_serial_or_ip`: an IPv4 address (e.g. "127.0.0.1", the only way
  // to reach a loopback camera), an Aravis device id ("Aravis-Fake-GV01") or a serial number. An id
  // or serial is resolved through discovery to its address. After opening, the serial number is
  // checked against `expected_serial` (when not empty) or against a serial given as the name.
  // Acquisition is stopped right away (a previous client may have left it running).
  // Throws CameraError when no such camera answers or the serial differs.
  static std::unique_ptr<AravisCamera> Open(const std::string& id_serial_or_ip,
                                            const std::string& expected_serial = "");
  ~AravisCamera() override;
  AravisCamera(const AravisCamera&) = delete;
  AravisCamera& operator=(const AravisCamera&) = delete;

  CameraIdentity Identity() const override;
  void Configure(const CameraSettings& settings) override;
  std::map<std::string, std::string> ReadBackFeatures() override;
  double SetExposureUs(double exposure_us) override;
  double ExposureUs() override;
  void WriteExposureUs(double exposure_us) override;
  TransferStats Transfer() const override;
  void StartStream() override;
  void StopStream() override;
  bool streaming() const override;
  std::optional<RawFrame> WaitFrame(std::chrono::milliseconds timeout) override;
  int Flush() override;
  void SoftwareTrigger() override;
  bool HasExposureChunks() const override;
  ExposureCheck exposure_check() const override;

  // Stream counters from Aravis (completed buffers, failures, underruns, missing packets, ...).
  std::map<std::string, std::uint64_t> StreamStatistics() const;
  // Payload size in bytes of one frame as configured.
  int PayloadBytes() const;
  // Warm-up frames discarded by StartStream() so far.
  int warmup_discarded() const;
  // GigE Vision packet size in use (bytes), 0 for non-GigE cameras.
  int PacketSizeBytes() const;
  // `feature` as the camera describes it, under TriggerSelector `selector` when not empty (the
  // selector is put back afterwards).
  FeatureInfo Describe(const std::string& feature, const std::string& selector = "");
  // Whether the camera declares GVCP packet resend (GigE Vision capability register; false for
  // other transports).
  bool DeclaresPacketResend();
  // The pixel-shaping features the camera has (acquisition/pixel_pipeline.h), as found and as left
  // by the last Configure (empty before).
  std::vector<PixelFeatureState> PixelPipeline() const;
  // What makes the sensor a colour one (a PixelColorFilter, Bayer formats offered), or "" for a
  // monochrome sensor. Configure refuses a raw mosaic (a Mono format whose PixelColorFilter is
  // not None); a colour camera's own interpolated Mono output is accepted and named.
  std::string ColourSensor();
  // Puts back every feature the first Configure changed, as it was found (stopped first); returns
  // " The camera was put back as it was found." or what could not be. Configure again to use it.
  std::string RestoreFound();
  // When a command is done with the camera, however it ended: stops the stream, then puts back
  // what Configure changed (RestoreFound) when `restore` is true. Never throws: returns what was
  // done, as a sentence for the user ("" when never configured).
  std::string LeaveAsFound(bool restore) noexcept;
  // The exposure's bounds (us) as read by the last Configure ({0, 0} before).
  std::pair<double, double> ExposureBoundsUs() const;

 private:
  struct Impl;  // acquisition/aravis_internal.h (acquisition-internal)
  explicit AravisCamera(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace irdist
