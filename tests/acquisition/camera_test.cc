// Tests of acquisition/camera.cc: the settings' validation names the field at fault, every frame
// status has its own name, and the Camera interface's defaults.
#include "acquisition/camera.h"

#include <gtest/gtest.h>

#include <functional>
#include <set>
#include <string>
#include <vector>

namespace irdist {
namespace {

struct BadSetting {
  std::function<void(CameraSettings&)> spoil;
  const char* field;  // the message must name it
};

TEST(CameraSettings, EveryInvalidFieldIsRefusedByName) {
  std::string why;
  ASSERT_TRUE(CameraSettings().IsValid(&why)) << why;
  const std::vector<BadSetting> cases = {
      {[](CameraSettings& s) { s.pixel_format = "RGB8"; }, "pixel_format"},
      {[](CameraSettings& s) { s.trigger_source = ""; }, "trigger_source"},
      {[](CameraSettings& s) { s.width = -1; }, "width"},
      {[](CameraSettings& s) { s.offset_y = -4; }, "offsets"},
      {[](CameraSettings& s) { s.frame_rate_hz = -1.0; }, "frame_rate_hz"},
      {[](CameraSettings& s) { s.exposure_us = 0.0; }, "exposure_us"},
      {[](CameraSettings& s) { s.packet_size = -1; }, "packet_size"},
      {[](CameraSettings& s) { s.socket_buffer_bytes = -1; }, "socket_buffer_bytes"},
      {[](CameraSettings& s) { s.buffer_count = 1; }, "buffer_count"},
      {[](CameraSettings& s) { s.warmup_frames = -1; }, "warmup_frames"},
      {[](CameraSettings& s) { s.frame_retention_ms = 0; }, "frame_retention_ms"},
      {[](CameraSettings& s) { s.readback_tolerance = 0.5; }, "readback_tolerance"},
      {[](CameraSettings& s) { s.packet_request_ratio = 0.0; }, "packet_request_ratio"},
  };
  for (const BadSetting& bad : cases) {
    CameraSettings settings;
    bad.spoil(settings);
    why.clear();
    EXPECT_FALSE(settings.IsValid(&why)) << bad.field;
    EXPECT_NE(why.find(bad.field), std::string::npos) << "'" << why << "' names not " << bad.field;
  }
}

TEST(CameraSettings, UntriggeredCameraNeedsNoTriggerSourceAndEveryMonoFormatIsValid) {
  CameraSettings settings;
  settings.triggered = false;
  settings.trigger_source = "";
  EXPECT_TRUE(settings.IsValid(nullptr));
  for (const char* format : {"Mono8", "Mono10", "Mono10p", "Mono12", "Mono12p", "Mono12Packed",
                             "Mono14", "Mono16"}) {
    settings.pixel_format = format;
    EXPECT_TRUE(settings.IsValid(nullptr)) << format;
  }
  settings.pixel_format = "mono12";  // GenICam names are case-sensitive
  EXPECT_FALSE(settings.IsValid(nullptr));
}

TEST(FrameStatus, EveryStatusHasItsOwnName) {
  const FrameStatus all[] = {FrameStatus::kOk,           FrameStatus::kTimeout,
                             FrameStatus::kMissingPackets, FrameStatus::kWrongPacketId,
                             FrameStatus::kSizeMismatch, FrameStatus::kAborted,
                             FrameStatus::kUnderrun,     FrameStatus::kFilling,
                             FrameStatus::kWrongExposure, FrameStatus::kUnknown};
  std::set<std::string> names;
  for (FrameStatus status : all) names.insert(FrameStatusName(status));
  EXPECT_EQ(names.size(), std::size(all));
  EXPECT_STREQ(FrameStatusName(FrameStatus::kOk), "ok");
  EXPECT_STREQ(FrameStatusName(FrameStatus::kMissingPackets), "missing_packets");
  EXPECT_STREQ(FrameStatusName(FrameStatus::kWrongExposure), "wrong_exposure");
  EXPECT_STREQ(FrameStatusName(static_cast<FrameStatus>(99)), "unknown");
}

// A camera that records the interface's default behaviour.
class MinimalCamera : public Camera {
 public:
  std::vector<double> set_calls;
  CameraIdentity Identity() const override { return {}; }
  void Configure(const CameraSettings&) override {}
  std::map<std::string, std::string> ReadBackFeatures() override { return {}; }
  double SetExposureUs(double exposure_us) override {
    set_calls.push_back(exposure_us);
    return exposure_us;
  }
  double ExposureUs() override { return set_calls.empty() ? 0.0 : set_calls.back(); }
  void StartStream() override {}
  void StopStream() override {}
  bool streaming() const override { return false; }
  std::optional<RawFrame> WaitFrame(std::chrono::milliseconds) override { return std::nullopt; }
  int Flush() override { return 0; }
  void SoftwareTrigger() override {}
  bool HasExposureChunks() const override { return false; }
};

TEST(Camera, DefaultWriteExposureGoesThroughSetExposureAndNoTransferCounters) {
  MinimalCamera camera;
  camera.WriteExposureUs(12000.0);
  ASSERT_EQ(camera.set_calls.size(), 1u);
  EXPECT_DOUBLE_EQ(camera.set_calls[0], 12000.0);
  const TransferStats transfer = camera.Transfer();
  EXPECT_EQ(transfer.resent_packets, 0u);
  EXPECT_EQ(transfer.missing_packets, 0u);
}

TEST(CameraIdentity, BriefReportNamesVendorModelSerialAndAddress) {
  CameraIdentity identity{"Acme", "Cam-1", "S42", "1.2", "10.0.0.5"};
  const std::string report = identity.BriefReport();
  for (const char* part : {"Acme", "Cam-1", "S42", "1.2", "10.0.0.5"}) {
    EXPECT_NE(report.find(part), std::string::npos) << part << " missing in " << report;
  }
  identity.address.clear();
  EXPECT_EQ(identity.BriefReport().find(" at "), std::string::npos);
}

}  // namespace
}  // namespace irdist
