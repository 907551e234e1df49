// measure --track's parts without a GigE camera: the grabber's accounting of every frame (a
// scripted camera that drops, damages and mis-exposes frames, and an estimator slower than the
// camera), the track line's JSON, the bracket's check against the track, the latency quantiles
// and the exposure's refusal. The live command is tested in
// tests/integration/measure_track_test.cc.
#include "app/live/track_session.h"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <chrono>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <set>
#include <thread>

#include "app/inputs/errors.h"
#include "app/live/frame_grabber.h"
#include "app/live/track_output.h"

namespace irdist {
namespace {

// Each trigger starts a frame numbered 1, 2, ... (the GigE Vision block id); frames in `dropped`
// never come, those in `damaged` come failed, those in `other_exposure` at twice the exposure.
class ScriptedCamera : public Camera {
 public:
  std::set<std::uint64_t> dropped, damaged, other_exposure;

  CameraIdentity Identity() const override { return {}; }
  void Configure(const CameraSettings&) override {}
  std::map<std::string, std::string> ReadBackFeatures() override { return {}; }
  double SetExposureUs(double exposure_us) override { return exposure_us_ = exposure_us; }
  double ExposureUs() override { return exposure_us_; }
  void StartStream() override { streaming_ = true; }
  void StopStream() override { streaming_ = false; }
  bool streaming() const override { return streaming_; }
  std::optional<RawFrame> WaitFrame(std::chrono::milliseconds timeout) override {
    std::unique_lock<std::mutex> lock(mutex_);
    if (!ready_.wait_for(lock, timeout, [this] { return !queue_.empty(); })) return std::nullopt;
    RawFrame frame = queue_.front();
    queue_.pop_front();
    return frame;
  }
  int Flush() override {
    std::lock_guard<std::mutex> lock(mutex_);
    const int n = static_cast<int>(queue_.size());
    queue_.clear();
    return n;
  }
  void SoftwareTrigger() override {
    std::lock_guard<std::mutex> lock(mutex_);
    const std::uint64_t id = ++next_id_;
    if (dropped.count(id) != 0) return;
    RawFrame frame;
    frame.frame_id = id;
    frame.timestamp_ns = id * 20'000'000ULL;
    frame.status = damaged.count(id) != 0 ? FrameStatus::kMissingPackets : FrameStatus::kOk;
    if (frame.status == FrameStatus::kOk) frame.image = cv::Mat(4, 4, CV_16UC1, cv::Scalar(7));
    frame.chunk_exposure_us = exposure_us_ * (other_exposure.count(id) != 0 ? 2.0 : 1.0);
    queue_.push_back(frame);
    ready_.notify_one();
  }
  bool HasExposureChunks() const override { return true; }

 private:
  std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<RawFrame> queue_;
  std::uint64_t next_id_ = 0;
  double exposure_us_ = 0.0;
  bool streaming_ = false;
};

GrabberOptions Options() {
  GrabberOptions options;
  options.exposure_us = 8000.0;
  options.ahead = 2;
  options.frame_timeout = std::chrono::milliseconds(200);
  return options;
}

// Frame 1 is the warm-up; 6 is never sent, 9 comes damaged, 12 at another exposure. The
// estimator takes a frame every 3 ms while the camera delivers as fast as it is triggered, so
// most frames are replaced before they are taken.
TEST(FrameGrabber, EveryTriggeredFrameIsEstimatedSkippedOrLostAndCountedOnce) {
  ScriptedCamera camera;
  camera.dropped = {6};
  camera.damaged = {9};
  camera.other_exposure = {12};
  FrameGrabber grabber(
      camera, [&camera](int) { camera.SoftwareTrigger(); }, Options());
  grabber.Start();
  std::vector<GrabbedFrame> taken;
  while (taken.size() < 20) {
    if (auto f = grabber.Take(std::chrono::milliseconds(500))) taken.push_back(std::move(*f));
    std::this_thread::sleep_for(std::chrono::milliseconds(3));
  }
  grabber.Stop();
  const TrackCounters c = grabber.counters();
  EXPECT_EQ(c.lost, 2);            // 6 never sent (a gap in the ids), 9 damaged
  EXPECT_EQ(c.wrong_exposure, 1);  // 12
  EXPECT_EQ(c.triggered, c.received + c.lost + c.wrong_exposure);  // none in flight after Stop
  EXPECT_EQ(c.received, c.estimated + c.skipped + c.drained);
  EXPECT_GE(c.drained, 1);  // the frames in flight at Stop (2 triggers ahead)
  EXPECT_EQ(c.estimated, 20);
  for (std::size_t i = 1; i < taken.size(); ++i) {
    // Newest first, never twice; the frames between two taken were skipped, and counted.
    EXPECT_GT(taken[i].number, taken[i - 1].number);
    EXPECT_EQ(taken[i].number - taken[i - 1].number - 1,
              taken[i].counters.skipped - taken[i - 1].counters.skipped);
    EXPECT_NE(taken[i].raw.frame_id, 12u);
  }
  EXPECT_EQ(camera.ExposureUs(), 8000.0);
}

// A camera that stops sending: the frames in flight are lost at the timeout, and Take says none.
TEST(FrameGrabber, ACameraThatStopsSendingLosesTheFramesInFlightAndTakeReturnsNone) {
  ScriptedCamera camera;
  for (std::uint64_t id = 4; id < 1000; ++id) camera.dropped.insert(id);
  FrameGrabber grabber(
      camera, [&camera](int) { camera.SoftwareTrigger(); }, Options());
  grabber.Start();
  int got = 0;
  while (grabber.Take(std::chrono::milliseconds(600))) ++got;
  grabber.Stop();
  EXPECT_GE(got, 1);
  const TrackCounters c = grabber.counters();
  EXPECT_EQ(c.received, 2);  // 2 and 3 (1 the warm-up)
  EXPECT_EQ(c.triggered, c.received + c.lost);
  EXPECT_GE(c.lost, 2);
}

TrackSample TrackedFrame() {
  TrackSample s;
  s.estimate.mode = "track";
  s.estimate.bracket = 41;
  s.estimate.have_estimate = true;
  s.estimate.estimate.ok = true;
  s.estimate.estimate.d_mm = 2000.5;
  s.estimate.estimate.d_std_mm = 2.5;
  s.acquisition = "triggered";
  s.frame = 41;
  s.camera_frame_id = 42;
  s.exposure_ms = 8.0;
  s.filtered = true;
  s.filter.position_mm = {2000.25};
  s.filter.position_sd_mm = {0.75};
  s.filter.velocity_mm_per_s = {-1.5};
  s.filter.velocity_sd_mm_per_s = {4.0};
  s.filter.used = true;
  s.filter.frames = 12;
  s.counters.received = 50;
  s.counters.skipped = 8;
  return s;
}

TEST(TrackJson, MeasuresSchemaWithTheModeTheFilterAndTheCounters) {
  const YAML::Node j = YAML::Load(TrackJson(TrackedFrame()));
  EXPECT_EQ(j["schema"].as<std::string>(), "irdist.measure/2");
  EXPECT_EQ(j["mode"].as<std::string>(), "track");
  EXPECT_EQ(j["acquisition"].as<std::string>(), "triggered");
  EXPECT_EQ(j["frame"].as<int>(), 41);
  EXPECT_EQ(j["camera_frame_id"].as<int>(), 42);
  EXPECT_DOUBLE_EQ(j["d_mm"].as<double>(), 2000.5);
  EXPECT_DOUBLE_EQ(j["d_se_mm"].as<double>(), 2.5);
  EXPECT_DOUBLE_EQ(j["track"]["d_mm"].as<double>(), 2000.25);
  EXPECT_DOUBLE_EQ(j["track"]["d_se_mm"].as<double>(), 0.75);
  EXPECT_DOUBLE_EQ(j["track"]["v_mm_per_s"].as<double>(), -1.5);
  EXPECT_DOUBLE_EQ(j["track"]["v_se_mm_per_s"].as<double>(), 4.0);
  EXPECT_EQ(j["track"]["frames"].as<int>(), 12);
  EXPECT_EQ(j["counters"]["skipped"].as<int>(), 8);
  EXPECT_TRUE(j["check"].IsNull());
}

TEST(TrackJson, ABracketLineHasNoFrameAndCarriesItsCheck) {
  TrackSample s = TrackedFrame();
  s.estimate.mode = "bracket";
  s.frame = -1;
  s.filtered = false;
  s.check.assessed = true;
  s.check.track_d_mm = 2001.0;
  s.check.z = -0.5;
  const YAML::Node j = YAML::Load(TrackJson(s));
  EXPECT_EQ(j["mode"].as<std::string>(), "bracket");
  EXPECT_TRUE(j["frame"].IsNull());
  EXPECT_TRUE(j["track"].IsNull());
  EXPECT_DOUBLE_EQ(j["check"]["track_d_mm"].as<double>(), 2001.0);
  EXPECT_TRUE(j["check"]["agree"].as<bool>());
}

// The track's distance is carried to the bracket's time by its velocity; the se adds the
// velocity's over the gap.
TEST(CheckAgainstTrack, CarriesTheTrackToTheBracketAndComparesInStandardErrors) {
  TrackState last;
  last.time_s = 10.0;
  last.position_mm = {2000.0};
  last.position_sd_mm = {3.0};
  last.velocity_mm_per_s = {100.0};
  last.velocity_sd_mm_per_s = {20.0};
  MeasureSample bracket;
  bracket.have_estimate = true;
  bracket.estimate.ok = true;
  bracket.estimate.d_mm = 2020.0;
  bracket.estimate.d_std_mm = 4.0;
  TrackCheck c = CheckAgainstTrack(last, true, 10.2, bracket);
  ASSERT_TRUE(c.assessed);
  EXPECT_NEAR(c.track_d_mm, 2020.0, 1e-9);
  EXPECT_NEAR(c.track_se_mm, 5.0, 1e-9);  // sqrt(3^2 + (20 x 0.2)^2)
  EXPECT_NEAR(c.z, 0.0, 1e-9);
  EXPECT_TRUE(c.agree);
  bracket.estimate.d_mm = 2020.0 + 4.0 * std::sqrt(41.0);  // 4 combined se away
  c = CheckAgainstTrack(last, true, 10.2, bracket);
  EXPECT_NEAR(c.z, 4.0, 1e-9);
  EXPECT_FALSE(c.agree);
  EXPECT_FALSE(CheckAgainstTrack(last, false, 10.2, bracket).assessed);  // no track yet
}

TEST(TrackStats, LatencyQuantilesAndTheRatioOfEstimatesToFrames) {
  TrackStats stats;
  for (int i = 1; i <= 100; ++i) {
    TrackSample s = TrackedFrame();
    s.estimate.latency_ms = 0.1 * i;  // 0.1 .. 10 ms
    stats.Add(s);
  }
  EXPECT_NEAR(stats.LatencyQuantileMs(0.5), 5.0, 0.011);
  EXPECT_NEAR(stats.LatencyQuantileMs(0.95), 9.5, 0.011);
  TrackCounters c;
  c.received = 200;
  const std::string report = stats.Report(2.0, c);
  EXPECT_NE(report.find("Tracked 100 frames in 2.00 s (50.00 estimates/s; the camera delivered "
                        "100.00 frames/s: ratio 0.500)"),
            std::string::npos)
      << report;
  EXPECT_NE(report.find(", max 10.00 ms"), std::string::npos) << report;
}

TEST(TrackExposureMs, TheModelsReferenceByDefaultAndOutsideTheCalibrationRefused) {
  CalibrationModel model;
  model.provenance.t_ref_ms = 8.0;
  model.ranges.t_ref_min_ms = model.ranges.t_ref_max_ms = 8.0;
  model.ranges.t_min_ms = 30.0;
  model.ranges.t_max_ms = 36.0;
  MeasureArgs args;
  args.model = "model.yaml";
  EXPECT_DOUBLE_EQ(TrackExposureMs(args, model), 8.0);
  args.exposure_ms = 33.0;
  EXPECT_DOUBLE_EQ(TrackExposureMs(args, model), 33.0);
  args.exposure_ms = 20.0;
  EXPECT_THROW(TrackExposureMs(args, model), UsageError);
}

}  // namespace
}  // namespace irdist
