// A bracket against the virtual rig (sim/): the frames carry the exposures requested, in order.
// The rig renders each frame from radiometry with the exposure latched for it, so the emitter's
// integrated signal in each frame must scale like the noise-free ground truth for its exposure.
#include <arv.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <string>

#include "acquisition/aravis_camera.h"
#include "acquisition/bracket.h"
#include "sim/camera_server.h"
#include "sim/virtual_rig.h"
#include "tests/loopback_gvcp.h"
#include "tests/virtual_rig_with.h"

namespace irdist {
namespace {

// Signal of the frame above its background (the median gray level), in gray levels.
double SignalAboveBackground(const cv::Mat& image) {
  std::vector<std::uint16_t> values(image.begin<std::uint16_t>(), image.end<std::uint16_t>());
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  const double background = values[values.size() / 2];
  double sum = 0.0;
  for (auto it = image.begin<std::uint16_t>(); it != image.end<std::uint16_t>(); ++it) {
    if (*it > background + 8) sum += *it - background;
  }
  return sum;
}

TEST(BracketVirtualRig, FiveExposureBracketCarriesTheRequestedExposuresInOrder) {
  testing::LoopbackGvcpLock lock;
  sim::VirtualRigOverrides overrides;
  overrides.serial = "IRDVACQ1";
  overrides.seed = 7;
  auto rig = sim::VirtualRig::Start(IRDIST_SOURCE_DIR "/recipes/rigs/virtual.yaml", overrides);
  const double slide_mm = 1500.0;
  const double bias_ma = 500.0;
  rig->world().SetPose(slide_mm, 0.0, 0.0, false);
  rig->world().SetCurrent(bias_ma);

  auto camera = AravisCamera::Open(rig->Info().camera_address, rig->Info().serial);
  CameraSettings settings;
  settings.pixel_format = "Mono12";
  settings.trigger_source = "Software";
  camera->Configure(settings);

  BracketOptions options;
  // Neighbours differ by >= 1.5x, so a frame taken with its neighbour's exposure cannot pass.
  options.exposures_us = {8000.0, 24000.0, 12000.0, 36000.0, 16000.0};
  options.trigger_source = "Software";
  BracketCapture capture(*camera, options);
  const BracketResult result = capture.Capture([&](int) { camera->SoftwareTrigger(); });
  camera->StopStream();
  ASSERT_TRUE(result.complete) << result.BriefReport() << " / " << capture.stats().BriefReport();
  ASSERT_EQ(result.frames.size(), 5u);

  // Each frame's signal, relative to the first frame's, must be nearest (in log ratio) to the
  // ground truth of its own exposure among all the bracket's exposures, and within 15% of it (the
  // sensor model is not perfectly linear, so exact proportionality is not expected).
  std::vector<double> truth_ratio;
  const double truth0 =
      rig->Describe(slide_mm, 0.0, 0.0, bias_ma, options.exposures_us[0]).signal_e;
  for (double exposure_us : options.exposures_us) {
    const auto truth = rig->Describe(slide_mm, 0.0, 0.0, bias_ma, exposure_us);
    EXPECT_FALSE(truth.saturated);
    truth_ratio.push_back(truth.signal_e / truth0);
  }
  const double signal0 = SignalAboveBackground(result.frames[0].image);
  ASSERT_GT(signal0, 0.0);
  for (size_t i = 0; i < result.frames.size(); ++i) {
    const BracketFrame& frame = result.frames[i];
    EXPECT_NEAR(frame.actual_exposure_us, options.exposures_us[i], 1.0);
    const double measured = SignalAboveBackground(frame.image) / signal0;
    size_t nearest = 0;
    for (size_t k = 1; k < truth_ratio.size(); ++k) {
      if (std::fabs(std::log(measured / truth_ratio[k])) <
          std::fabs(std::log(measured / truth_ratio[nearest]))) {
        nearest = k;
      }
    }
    EXPECT_EQ(nearest, i) << "frame " << i << " looks taken with " << options.exposures_us[nearest]
                          << " us";
    EXPECT_NEAR(measured, truth_ratio[i], 0.15 * truth_ratio[i]) << "frame " << i;
  }
  EXPECT_EQ(capture.stats().lost, 0);
  camera.reset();
  rig->Stop();
}

// A virtual rig with a Software-triggered camera opened on it, 256 x 256 Mono12 frames.
struct SmallRig {
  explicit SmallRig(const std::string& serial, bool chunks = true, int width = 256,
                    double time_scale = 10.0,
                    const std::string& rig_path = IRDIST_SOURCE_DIR "/recipes/rigs/virtual.yaml") {
    sim::VirtualRigOverrides overrides;
    overrides.serial = serial;
    overrides.seed = 11;
    overrides.time_scale = time_scale;
    rig = sim::VirtualRig::Start(rig_path, overrides);
    rig->world().SetPose(1500.0, 0.0, 0.0, false);
    rig->world().SetCurrent(500.0);
    camera = AravisCamera::Open(rig->Info().camera_address, rig->Info().serial);
    CameraSettings settings;
    settings.pixel_format = "Mono12";
    settings.trigger_source = "Software";
    settings.width = width;
    settings.height = width;
    settings.exposure_chunks = chunks;
    camera->Configure(settings);
  }
  ~SmallRig() {
    camera.reset();
    rig->Stop();
  }
  // The camera's own record of every frame it exposed, by GVSP block id.
  std::map<std::uint64_t, double> ExposureByBlockId() const {
    std::map<std::uint64_t, double> out;
    for (const auto& record : rig->camera().RecentFrames()) out[record.block_id] = record.exposure_us;
    return out;
  }
  testing::LoopbackGvcpLock lock;
  std::unique_ptr<sim::VirtualRig> rig;
  std::unique_ptr<AravisCamera> camera;
};

BracketOptions FiveExposures() {
  BracketOptions options;
  options.exposures_us = {8000.0, 24000.0, 12000.0, 36000.0, 16000.0};
  options.trigger_source = "Software";
  options.max_retries = 6;
  return options;
}

// Takes `brackets` brackets; every frame delivered must carry, by the camera's own record of the
// frame with its id, the exposure it is labelled with. Returns the capture's stats.
CaptureStats ExpectNoMislabelledFrame(SmallRig& small, const BracketOptions& options,
                                      int brackets) {
  BracketCapture capture(*small.camera, options);
  std::vector<BracketFrame> frames;
  const auto wall_ns = [] {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(
               std::chrono::system_clock::now().time_since_epoch())
        .count();
  };
  for (int b = 0; b < brackets; ++b) {
    std::vector<std::int64_t> triggered_ns;
    BracketResult result = capture.Capture([&](int) {
      triggered_ns.push_back(wall_ns());
      small.camera->SoftwareTrigger();
    });
    // Each frame is stamped when received: after its trigger, before Capture() returned.
    for (const BracketFrame& frame : result.frames) {
      EXPECT_GE(frame.host_time_ns, triggered_ns.front());
      EXPECT_LE(frame.host_time_ns, wall_ns());
    }
    EXPECT_TRUE(result.complete) << result.BriefReport() << " / " << capture.stats().BriefReport();
    for (auto& frame : result.frames) frames.push_back(std::move(frame));
  }
  small.camera->StopStream();
  const auto truth = small.ExposureByBlockId();
  for (const BracketFrame& frame : frames) {
    const auto it = truth.find(frame.frame_id);
    EXPECT_NE(it, truth.end()) << "frame id " << frame.frame_id << " not exposed by the camera";
    if (it == truth.end()) continue;
    EXPECT_DOUBLE_EQ(it->second, frame.requested_exposure_us)
        << "frame " << frame.frame_id << " labelled " << frame.requested_exposure_us
        << " us was taken with " << it->second << " us";
    EXPECT_DOUBLE_EQ(frame.actual_exposure_us, frame.requested_exposure_us);
  }
  EXPECT_EQ(frames.size(), static_cast<size_t>(brackets) * options.exposures_us.size());
  return capture.stats();
}

TEST(BracketVirtualRig, PipelinedBracketsProgramTheNextExposureDuringReadout) {
  SmallRig small("IRDVACQ2");
  ASSERT_TRUE(small.camera->HasExposureChunks());
  const CaptureStats stats = ExpectNoMislabelledFrame(small, FiveExposures(), 4);
  EXPECT_EQ(stats.pipelined_frames, 4 * 4);  // every frame but each bracket's last
  EXPECT_EQ(stats.lost, 0);
}

// Fault: the camera applies ExposureTime writes late (up to 30 ms, so two writes may also land in
// the reverse order). Whether pipelined (checked by ChunkExposureTime) or serial without chunks
// (checked by read-back order), no frame may carry a label of another exposure.
TEST(BracketVirtualRig, DelayedOrReorderedExposureWritesNeverMislabelAFrame) {
  for (const bool chunks : {true, false}) {
    SmallRig small(chunks ? "IRDVACQ3" : "IRDVACQ4", chunks);
    small.rig->camera().SetExposureWriteDelayMs(30.0);
    const CaptureStats stats = ExpectNoMislabelledFrame(small, FiveExposures(), 4);
    EXPECT_GT(small.rig->camera().Stats().exposure_writes_delayed, 0u);
    // The fault was met: frames were retaken or read-backs waited for the late write.
    EXPECT_GT(stats.wrong_exposure + stats.exposure_rereads, 0) << stats.BriefReport();
    EXPECT_EQ(stats.lost, 0) << stats.BriefReport();
  }
}

// Exposure chunks on (every frame carries its own), dropped from the first frame (a camera
// declaring them whose frames carry none) and stopping mid-run: every bracket complete, every
// frame labelled with the exposure the camera's own record gives it; without chunks the capture
// falls back to read-backs with one notice naming the chunk.
TEST(BracketVirtualRig, ExposureChunksOnOffAndStoppingMidRunLoseNoFrame) {
  struct Case {
    const char* serial;
    int drop_from_frame;  // virtual.camera.drop_exposure_chunks_from_frame (0 = never)
    const char* notice;   // in the fallback's notice ("" = none)
  };
  // Frame 1 is Configure's warm-up; a bracket is 5 frames: 9 stops them in the second bracket.
  for (const Case& c : {Case{"IRDVCHK0", 0, ""}, Case{"IRDVCHK1", 1, "no frame carried one"},
                        Case{"IRDVCHK9", 9, "the chunks stopped after"}}) {
    SCOPED_TRACE(c.serial);
    const std::string rig_path = testing::VirtualRigWithCameraKeys(
        c.serial, "    drop_exposure_chunks_from_frame: " + std::to_string(c.drop_from_frame) + "\n");
    SmallRig small(c.serial, true, 256, 10.0, rig_path);
    ASSERT_TRUE(small.camera->HasExposureChunks());  // declared and turned on
    const CaptureStats stats = ExpectNoMislabelledFrame(small, FiveExposures(), 4);
    EXPECT_EQ(stats.lost, 0) << stats.BriefReport();
    EXPECT_EQ(stats.wrong_exposure, 0) << stats.BriefReport();
    if (c.drop_from_frame == 0) {
      EXPECT_TRUE(stats.exposure_notice.empty()) << stats.exposure_notice;
      EXPECT_EQ(stats.pipelined_frames, 4 * 4);
      continue;
    }
    EXPECT_EQ(stats.without_chunk, 1) << stats.BriefReport();
    EXPECT_NE(stats.exposure_notice.find(c.notice), std::string::npos) << stats.exposure_notice;
    EXPECT_NE(stats.exposure_notice.find("ChunkExposureTime"), std::string::npos);
    EXPECT_LT(stats.pipelined_frames, 4 * 4);
  }
}

// Control first: while another client holds the camera's control channel, Open refuses before it
// writes any feature and names the holder from the camera's primary application register; once
// that client has left, Open takes control.
TEST(BracketVirtualRig, AnotherControllerHoldingTheCameraIsNamedBeforeAnyWrite) {
  testing::LoopbackGvcpLock lock;
  sim::VirtualRigOverrides overrides;
  overrides.serial = "IRDVCTL1";
  auto rig = sim::VirtualRig::Start(IRDIST_SOURCE_DIR "/recipes/rigs/virtual.yaml", overrides);
  GError* error = nullptr;
  ArvCamera* other = arv_camera_new("127.0.0.1", &error);
  ASSERT_EQ(error, nullptr) << error->message;
  ArvGvDevice* other_device = ARV_GV_DEVICE(arv_camera_get_device(other));
  if (arv_gv_device_is_controller(other_device) == FALSE) {
    ASSERT_TRUE(arv_gv_device_take_control(other_device, nullptr));
  }
  const auto writes_before = rig->camera().Stats().control_requests;
  try {
    AravisCamera::Open("127.0.0.1", "IRDVCTL1");
    ADD_FAILURE() << "opened a camera another client controls";
  } catch (const CameraError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("is controlled by the application at 127.0.0.1 port"),
              std::string::npos) << message;
    EXPECT_NE(message.find("writes no feature without control"), std::string::npos);
  }
  EXPECT_GT(rig->camera().Stats().control_requests, writes_before);  // it did ask
  g_object_unref(other);  // leaves control
  auto camera = AravisCamera::Open("127.0.0.1", "IRDVCTL1");
  camera->Configure(CameraSettings{});
  camera.reset();
  rig->Stop();
}

// virtual.camera.packet_resend: false serves a camera without GVCP resend (capability bit clear).
TEST(BracketVirtualRig, RigKeySwitchesPacketResendOff) {
  {
    SmallRig with("IRDVRSD1");  // one rig at a time: each holds the loopback GVCP lock
    EXPECT_TRUE(with.camera->DeclaresPacketResend());
  }
  SmallRig without("IRDVRSD0", true, 256, 10.0,
                   testing::VirtualRigWithCameraKeys("IRDVRSD0", "    packet_resend: false\n"));
  EXPECT_FALSE(without.camera->DeclaresPacketResend());
}

// exposure_check: readback turns the camera's chunks off; chunk on a camera declaring them works.
TEST(BracketVirtualRig, ExposureCheckReadbackTurnsChunksOff) {
  SmallRig small("IRDVCHKR");
  CameraSettings settings;
  settings.pixel_format = "Mono12";
  settings.trigger_source = "Software";
  settings.width = 256;
  settings.height = 256;
  settings.exposure_check = ExposureCheck::kReadback;
  small.camera->Configure(settings);
  EXPECT_FALSE(small.camera->HasExposureChunks());
  EXPECT_EQ(small.camera->ReadBackFeatures()["ChunkModeActive"], "false");
  const CaptureStats stats = ExpectNoMislabelledFrame(small, FiveExposures(), 2);
  EXPECT_EQ(stats.pipelined_frames, 0);
  EXPECT_TRUE(stats.exposure_notice.empty());
  settings.exposure_check = ExposureCheck::kChunk;
  small.camera->Configure(settings);
  EXPECT_TRUE(small.camera->HasExposureChunks());
}

// GigE packet loss: the grabber asks for the lost packets again and the camera resends them, so
// full-size frames at 1% and 5% loss all arrive complete.
TEST(BracketVirtualRig, PacketLossIsRecoveredByResendWithNoFrameLost) {
  for (const double ratio : {0.01, 0.05}) {
    SmallRig small(ratio < 0.02 ? "IRDVACQ5" : "IRDVACQ6", true, 1024);
    small.rig->camera().SetLostPacketRatio(ratio);
    BracketCapture capture(*small.camera, FiveExposures());
    for (int b = 0; b < 3; ++b) {
      const BracketResult result = capture.Capture([&](int) { small.camera->SoftwareTrigger(); });
      EXPECT_TRUE(result.complete) << result.BriefReport();
    }
    small.camera->StopStream();
    const CaptureStats& stats = capture.stats();
    EXPECT_EQ(stats.lost, 0) << stats.BriefReport();
    EXPECT_EQ(stats.received, 15) << stats.BriefReport();
    EXPECT_GT(small.rig->camera().Stats().packets_lost, 0u);
    EXPECT_GT(stats.transfer.resent_packets, 0u) << stats.BriefReport();
    EXPECT_GT(small.rig->camera().Stats().packets_resent, 0u);
  }
}

}  // namespace
}  // namespace irdist

namespace irdist {
namespace {

// GVSP packet loss at 1% and 5%, with the camera resending and without: no frame the grabber
// completed is ever called a duplicate (a failed buffer's id, 0 after a lost leader, never moves
// the frame identity), and every frame accepted carries, by the camera's own record of its id,
// the exposure it is labelled with. With resend no frame is lost.
TEST(BracketVirtualRig, UnderPacketLossNoCompleteFrameIsCalledADuplicate) {
  for (const bool resend : {true, false}) {
    for (const double ratio : {0.01, 0.05}) {
      SCOPED_TRACE(std::string(resend ? "resend" : "no resend") + ", loss " +
                   std::to_string(ratio));
      SmallRig small(resend ? "IRDVACQ7" : "IRDVACQ8", true, 96);
      small.rig->camera().SetPacketResend(resend);
      small.camera->Configure([] {
        CameraSettings settings;  // again: the grabber reads the resend capability here
        settings.pixel_format = "Mono12";
        settings.trigger_source = "Software";
        settings.width = 96;
        settings.height = 96;
        return settings;
      }());
      small.rig->camera().SetLostPacketRatio(ratio);
      BracketOptions options = FiveExposures();
      options.max_retries = 10;
      BracketCapture capture(*small.camera, options);
      std::vector<BracketFrame> frames;
      for (int b = 0; b < 4; ++b) {
        BracketResult result = capture.Capture([&](int) { small.camera->SoftwareTrigger(); });
        if (resend) EXPECT_TRUE(result.complete) << result.BriefReport();
        for (auto& frame : result.frames) frames.push_back(std::move(frame));
      }
      small.camera->StopStream();
      const CaptureStats& stats = capture.stats();
      EXPECT_EQ(stats.duplicates, 0) << stats.BriefReport();
      if (resend) EXPECT_EQ(stats.lost, 0) << stats.BriefReport();
      if (!resend) EXPECT_EQ(stats.transfer.resent_packets, 0u) << stats.BriefReport();
      // Lost packets show as incomplete frames (a failed buffer), never as silence.
      if (!resend && ratio > 0.02) EXPECT_GT(stats.damaged, 0) << stats.BriefReport();
      const auto truth = small.ExposureByBlockId();
      for (const BracketFrame& frame : frames) {
        const auto it = truth.find(frame.frame_id);
        ASSERT_NE(it, truth.end()) << "frame id " << frame.frame_id << " never exposed";
        EXPECT_DOUBLE_EQ(it->second, frame.requested_exposure_us);
      }
      std::printf("%s, loss %.2f: %s\n", resend ? "resend" : "no resend", ratio,
                  stats.BriefReport().c_str());
    }
  }
}

}  // namespace
}  // namespace irdist

namespace irdist {
namespace {

// Mono12p end to end: the virtual camera packs its 12-bit values (PFNC), the grabber unpacks them:
// the bracket's frames carry 12-bit values whose signal matches the same bracket in Mono12.
TEST(BracketVirtualRig, Mono12pBracketMatchesMono12) {
  SmallRig small("IRDVACQ9", true, 256);
  std::vector<double> signal[2];
  for (const char* format : {"Mono12", "Mono12p"}) {
    CameraSettings settings;
    settings.pixel_format = format;
    settings.trigger_source = "Software";
    settings.width = 256;
    settings.height = 256;
    settings.offset_x = 512;  // around the IRED's image at the sensor's centre
    settings.offset_y = 384;
    small.camera->Configure(settings);
    BracketCapture capture(*small.camera, FiveExposures());
    const BracketResult result = capture.Capture([&](int) { small.camera->SoftwareTrigger(); });
    small.camera->StopStream();
    ASSERT_TRUE(result.complete) << result.BriefReport();
    for (const BracketFrame& frame : result.frames) {
      EXPECT_EQ(frame.bit_depth, 12);
      double max_value = 0.0;
      cv::minMaxLoc(frame.image, nullptr, &max_value);
      EXPECT_LE(max_value, 4095.0);
      signal[std::string(format) == "Mono12p" ? 1 : 0].push_back(SignalAboveBackground(frame.image));
    }
  }
  for (size_t i = 0; i < signal[0].size(); ++i) {
    ASSERT_GT(signal[0][i], 0.0);
    EXPECT_NEAR(signal[1][i], signal[0][i], 0.05 * signal[0][i]) << "frame " << i;
  }
}

}  // namespace
}  // namespace irdist
