// The frame grabber (app/live/frame_grabber.h): its options, each bad field refused with its
// name, and its accounting of every frame against a scripted camera that drops, damages and
// mis-exposes frames, with an estimator slower than the camera.
#include "app/live/frame_grabber.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <utility>
#include <vector>

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

TEST(GrabberOptions, DefaultsAreValid) {
  std::string why = "not touched";
  EXPECT_TRUE(GrabberOptions().IsValid(&why));
  EXPECT_EQ(why, "");
}

TEST(GrabberOptions, RefusesEachBadFieldByName) {
  std::vector<std::pair<GrabberOptions, std::string>> cases;
  for (const double exposure_us : {0.0, -5.0, double(NAN), 2.0e8}) {
    GrabberOptions o;
    o.exposure_us = exposure_us;
    cases.emplace_back(o, "exposure_us");
  }
  for (const int ahead : {0, -1, 17}) {
    GrabberOptions o;
    o.ahead = ahead;
    cases.emplace_back(o, "ahead");
  }
  GrabberOptions timeout;
  timeout.frame_timeout = std::chrono::milliseconds(0);
  cases.emplace_back(timeout, "frame_timeout");
  for (const double tolerance : {0.0, 1.0, double(NAN)}) {
    GrabberOptions o;
    o.exposure_tolerance = tolerance;
    cases.emplace_back(o, "exposure_tolerance");
  }
  for (const auto& [options, field] : cases) {
    std::string why;
    EXPECT_FALSE(options.IsValid(&why)) << field;
    EXPECT_EQ(why.rfind(field, 0), 0u) << why;
  }
}

}  // namespace
}  // namespace irdist
