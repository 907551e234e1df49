// Tests of BracketCapture: the planning and the accounting against a scripted camera (every fault
// on demand), and a real bracket against Aravis's fake GigE Vision camera, whose pattern brightness
// tracks the exposure each frame was taken with.
#include "acquisition/bracket.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <deque>

#include "acquisition/aravis_camera.h"
#include "tests/acquisition/fake_camera_process.h"

namespace irdist {
namespace {

TEST(BracketOptions, DefaultsAreValid) {
  std::string why;
  EXPECT_TRUE(BracketOptions().IsValid(&why)) << why;
  BracketOptions bad;
  bad.exposures_us = {8000.0};
  EXPECT_FALSE(bad.IsValid(&why));
  bad = BracketOptions();
  bad.exposures_us[2] = -1.0;
  EXPECT_FALSE(bad.IsValid(&why));
  bad = BracketOptions();
  bad.max_retries = -1;
  EXPECT_FALSE(bad.IsValid(&why));
}

TEST(PlanBracket, PlainAndInterleavedOrders) {
  BracketOptions options;
  options.exposures_us = {8000.0, 30000.0, 32000.0};
  auto plan = PlanBracket(options);
  ASSERT_EQ(plan.size(), 3u);
  EXPECT_EQ(plan[0].role, FrameRole::kReference);
  EXPECT_EQ(plan[1].role, FrameRole::kMeasurement);
  EXPECT_DOUBLE_EQ(plan[2].exposure_us, 32000.0);
  options.interleave_reference = true;
  plan = PlanBracket(options);
  ASSERT_EQ(plan.size(), 4u);
  const double expected[] = {8000.0, 30000.0, 8000.0, 32000.0};
  for (size_t i = 0; i < plan.size(); ++i) {
    EXPECT_DOUBLE_EQ(plan[i].exposure_us, expected[i]);
    EXPECT_EQ(plan[i].frame_in_bracket, static_cast<int>(i));
  }
  EXPECT_STREQ(FrameRoleName(plan[2].role), "ref");
  EXPECT_STREQ(FrameRoleName(plan[3].role), "meas");
}

// A camera whose response to each trigger follows a script.
class ScriptedCamera : public Camera {
 public:
  // kLostLeader: a failed buffer as Aravis hands it back when the frame's leader packet was lost:
  // status missing_packets, frame id and timestamp 0.
  enum class Act { kDeliver, kDrop, kDamage, kRepeatLastThenDeliver, kWrongChunk, kLostLeader };
  std::deque<Act> script;
  std::vector<double> exposures_at_trigger;
  bool chunks = false;
  int chunk_triggers = -1;  // with chunks: triggers whose frame carries one (-1 = every one)
  ExposureCheck check = ExposureCheck::kAuto;
  std::uint64_t next_id = 1;  // GigE Vision 1.x block ids: 1..65535, then 1 again

  CameraIdentity Identity() const override { return {"Test", "Scripted", "S1", "1", ""}; }
  void Configure(const CameraSettings&) override {}
  std::map<std::string, std::string> ReadBackFeatures() override { return {}; }
  double SetExposureUs(double exposure_us) override { return exposure_us_ = exposure_us; }
  double ExposureUs() override { return exposure_us_; }
  void StartStream() override { streaming_ = true; }
  void StopStream() override { streaming_ = false; }
  bool streaming() const override { return streaming_; }
  std::optional<RawFrame> WaitFrame(std::chrono::milliseconds) override {
    if (queue_.empty()) return std::nullopt;
    RawFrame frame = queue_.front();
    queue_.pop_front();
    return frame;
  }
  int Flush() override {
    const int n = static_cast<int>(queue_.size());
    queue_.clear();
    return n;
  }
  void SoftwareTrigger() override {
    exposures_at_trigger.push_back(exposure_us_);
    const Act act = script.empty() ? Act::kDeliver : script.front();
    if (!script.empty()) script.pop_front();
    RawFrame frame;
    frame.status = FrameStatus::kOk;
    frame.image = cv::Mat(4, 4, CV_16UC1, cv::Scalar(static_cast<double>(exposure_us_ / 100.0)));
    const bool chunk_sent =
        chunk_triggers < 0 || static_cast<int>(exposures_at_trigger.size()) <= chunk_triggers;
    if (chunks && chunk_sent) frame.chunk_exposure_us = exposure_us_;
    switch (act) {
      case Act::kDeliver:
        break;
      case Act::kDrop:
        next_id = next_id == 65535 ? 1 : next_id + 1;
        timestamp_ += 1000;
        return;
      case Act::kDamage:
        frame.status = FrameStatus::kMissingPackets;
        frame.image = cv::Mat();
        break;
      case Act::kRepeatLastThenDeliver:
        if (last_.has_value()) queue_.push_back(*last_);
        break;
      case Act::kWrongChunk:
        frame.chunk_exposure_us = exposure_us_ * 2.0;
        break;
      case Act::kLostLeader:
        frame.status = FrameStatus::kMissingPackets;
        frame.image = cv::Mat();
        next_id = next_id == 65535 ? 1 : next_id + 1;
        timestamp_ += 1000;
        queue_.push_back(frame);  // id 0, timestamp 0
        return;
    }
    frame.frame_id = next_id;
    next_id = next_id == 65535 ? 1 : next_id + 1;
    timestamp_ += 1000;
    frame.timestamp_ns = timestamp_;
    last_ = frame;
    queue_.push_back(frame);
  }
  bool HasExposureChunks() const override { return chunks; }
  ExposureCheck exposure_check() const override { return check; }

 private:
  double exposure_us_ = 1000.0;
  bool streaming_ = false;
  std::deque<RawFrame> queue_;
  std::optional<RawFrame> last_;
  std::uint64_t timestamp_ = 0;
};

BracketOptions FastOptions() {
  BracketOptions options;
  options.exposures_us = {8000.0, 30000.0, 32000.0, 34000.0, 36000.0};
  options.trigger_source = "Software";
  options.frame_timeout = std::chrono::milliseconds(50);
  options.late_frame_window = std::chrono::milliseconds(0);
  return options;
}

TEST(BracketCapture, CleanBracketCarriesRequestedExposuresInOrder) {
  ScriptedCamera camera;
  BracketCapture capture(camera, FastOptions());
  std::vector<int> fired;
  const BracketResult result = capture.Capture([&](int i) {
    fired.push_back(i);
    camera.SoftwareTrigger();
  });
  ASSERT_TRUE(result.complete) << result.BriefReport();
  ASSERT_EQ(result.frames.size(), 5u);
  EXPECT_EQ(fired, (std::vector<int>{0, 1, 2, 3, 4}));
  for (size_t i = 0; i < 5; ++i) {
    EXPECT_DOUBLE_EQ(result.frames[i].requested_exposure_us, FastOptions().exposures_us[i]);
    EXPECT_DOUBLE_EQ(result.frames[i].actual_exposure_us, FastOptions().exposures_us[i]);
    EXPECT_DOUBLE_EQ(camera.exposures_at_trigger[i], FastOptions().exposures_us[i]);
    EXPECT_EQ(result.frames[i].image.at<std::uint16_t>(0, 0),
              static_cast<std::uint16_t>(FastOptions().exposures_us[i] / 100.0));
  }
  EXPECT_EQ(capture.stats().requested, 5);
  EXPECT_EQ(capture.stats().received, 5);
  EXPECT_EQ(capture.stats().retried, 0);
  EXPECT_EQ(capture.stats().lost, 0);
}

TEST(BracketCapture, EachFrameIsHandedOverBeforeTheNextTrigger) {
  ScriptedCamera camera;
  BracketCapture capture(camera, FastOptions());
  int fired = 0;
  std::vector<int> fired_when_seen;
  std::vector<double> seen_exposures_us;
  const BracketResult result = capture.Capture(
      [&](int) {
        ++fired;
        camera.SoftwareTrigger();
      },
      [&](const BracketFrame& frame) {
        fired_when_seen.push_back(fired);
        seen_exposures_us.push_back(frame.actual_exposure_us);
      });
  ASSERT_TRUE(result.complete) << result.BriefReport();
  EXPECT_EQ(fired_when_seen, (std::vector<int>{1, 2, 3, 4, 5}));
  EXPECT_EQ(seen_exposures_us, FastOptions().exposures_us);
}

TEST(BracketCapture, RetriesDroppedAndDamagedFramesAndDiscardsDuplicates) {
  using Act = ScriptedCamera::Act;
  ScriptedCamera camera;
  camera.next_id = 65533;  // the ids wrap during the bracket
  camera.script = {Act::kDeliver, Act::kDrop, Act::kDeliver, Act::kDamage, Act::kDeliver,
                   Act::kRepeatLastThenDeliver, Act::kDeliver};
  BracketCapture capture(camera, FastOptions());
  const BracketResult result = capture.Capture([&](int) { camera.SoftwareTrigger(); });
  ASSERT_TRUE(result.complete) << result.BriefReport();
  ASSERT_EQ(result.frames.size(), 5u);
  EXPECT_EQ(result.frames[1].retries, 1);  // dropped once
  EXPECT_EQ(result.frames[2].retries, 1);  // damaged once
  EXPECT_EQ(result.frames[3].retries, 0);
  EXPECT_EQ(result.frames[1].frame_id, 65535u);
  EXPECT_EQ(result.frames[2].frame_id, 2u);  // wrapped (the damaged frame was 1): accepted
  EXPECT_EQ(result.frames[4].frame_id, 4u);
  for (size_t i = 0; i < 5; ++i) {
    EXPECT_DOUBLE_EQ(result.frames[i].actual_exposure_us, FastOptions().exposures_us[i]);
  }
  const CaptureStats& stats = capture.stats();
  EXPECT_EQ(stats.requested, 5);
  EXPECT_EQ(stats.received, 5);
  EXPECT_EQ(stats.retried, 2);
  EXPECT_EQ(stats.timeouts, 1);
  EXPECT_EQ(stats.damaged, 1);
  EXPECT_EQ(stats.duplicates, 1);
  EXPECT_EQ(stats.lost, 0);
  EXPECT_GE(stats.id_gaps, 1);  // the dropped frame's id never arrived
  EXPECT_NE(stats.BriefReport().find("retried 2"), std::string::npos);
}

TEST(BracketCapture, GivesUpAfterMaxRetriesAndCountsTheLoss) {
  using Act = ScriptedCamera::Act;
  ScriptedCamera camera;
  camera.script = {Act::kDeliver, Act::kDrop, Act::kDrop, Act::kDrop};
  BracketOptions options = FastOptions();
  options.max_retries = 2;
  BracketCapture capture(camera, options);
  const BracketResult result = capture.Capture([&](int) { camera.SoftwareTrigger(); });
  EXPECT_FALSE(result.complete);
  EXPECT_EQ(result.frames.size(), 1u);
  EXPECT_NE(result.failure.find("frame 1"), std::string::npos) << result.failure;
  EXPECT_EQ(capture.stats().lost, 1);
  EXPECT_EQ(capture.stats().retried, 2);
  EXPECT_EQ(capture.stats().brackets_failed, 1);
}

// A failed buffer's id and timestamp (0 after a lost leader) never move the frame identity: the
// good frames after it are accepted, none is called a duplicate, and the failure is counted by its
// status. Ids from 0x9000 make a 0 look newer to 16-bit wrap arithmetic, so that later good ids
// would look older.
TEST(BracketCapture, LostLeaderBuffersNeverMakeLaterFramesDuplicates) {
  using Act = ScriptedCamera::Act;
  ScriptedCamera camera;
  camera.next_id = 0x9000;
  camera.script = {Act::kDeliver, Act::kLostLeader, Act::kDeliver, Act::kDeliver,
                   Act::kLostLeader, Act::kDeliver, Act::kDeliver, Act::kDeliver};
  BracketCapture capture(camera, FastOptions());
  for (int b = 0; b < 3; ++b) {
    const BracketResult result = capture.Capture([&](int) { camera.SoftwareTrigger(); });
    ASSERT_TRUE(result.complete) << result.BriefReport() << " / " << capture.stats().BriefReport();
  }
  const CaptureStats& stats = capture.stats();
  EXPECT_EQ(stats.duplicates, 0) << stats.BriefReport();
  EXPECT_EQ(stats.received, 15);
  EXPECT_EQ(stats.damaged, 2);
  EXPECT_EQ(stats.timeouts, 0) << stats.BriefReport();
  EXPECT_EQ(stats.failed_buffers.at("missing_packets"), 2);
  EXPECT_NE(stats.BriefReport().find("missing_packets 2"), std::string::npos);
}

// The stop message leads with the network when buffers came incomplete, with the trigger when
// nothing arrived.
TEST(BracketCapture, GivingUpNamesTheNetworkForLostPacketsAndTheTriggerForSilence) {
  using Act = ScriptedCamera::Act;
  for (const Act act : {Act::kLostLeader, Act::kDrop}) {
    ScriptedCamera camera;
    camera.script = {act, act, act};
    BracketCapture capture(camera, FastOptions());
    const BracketResult result = capture.Capture([&](int) { camera.SoftwareTrigger(); });
    ASSERT_FALSE(result.complete);
    const std::string& why = result.failure;
    const auto network = why.find("packets were lost");
    const auto trigger = why.find("trigger wiring");
    ASSERT_NE(trigger, std::string::npos) << why;
    if (act == Act::kLostLeader) {
      ASSERT_NE(network, std::string::npos) << why;
      EXPECT_LT(network, trigger) << why;
      for (const char* cause : {"cable", "MTU", "jumbo", "socket buffer", "packet delay"}) {
        EXPECT_NE(why.find(cause), std::string::npos) << cause << " in " << why;
      }
    } else {
      EXPECT_EQ(network, std::string::npos) << why;
      EXPECT_NE(why.find("nothing arrived"), std::string::npos) << why;
    }
  }
}

// Chunks that stop mid-run (a NIC dropping them, firmware ignoring ChunkEnable): the capture falls
// back to read-backs with one notice naming the chunk; no good frame is rejected or lost.
TEST(BracketCapture, ChunksStoppingMidRunFallBackToReadbackWithOneNotice) {
  ScriptedCamera camera;
  camera.chunks = true;
  camera.chunk_triggers = 3;
  BracketOptions options = FastOptions();
  std::vector<std::string> notices;
  options.on_notice = [&](const std::string& text) { notices.push_back(text); };
  BracketCapture capture(camera, options);
  for (int bracket = 0; bracket < 2; ++bracket) {
    const BracketResult result = capture.Capture([&](int) { camera.SoftwareTrigger(); });
    ASSERT_TRUE(result.complete) << result.BriefReport();
    for (size_t i = 0; i < result.frames.size(); ++i) {
      EXPECT_DOUBLE_EQ(result.frames[i].actual_exposure_us, options.exposures_us[i]);
      EXPECT_EQ(result.frames[i].exposure_from_chunk, bracket == 0 && i < 3) << i;
    }
  }
  ASSERT_EQ(notices.size(), 1u);
  EXPECT_NE(notices[0].find("ChunkExposureTime"), std::string::npos) << notices[0];
  EXPECT_NE(notices[0].find("stopped after 3 frames"), std::string::npos) << notices[0];
  EXPECT_EQ(capture.stats().exposure_notice, notices[0]);
  EXPECT_EQ(capture.stats().without_chunk, 1);
  EXPECT_EQ(capture.stats().wrong_exposure, 0);
  EXPECT_EQ(capture.stats().lost, 0);
  // The frame without its chunk was retaken once, read back, and every later one read back.
  EXPECT_EQ(capture.stats().retried, 1);
}

TEST(BracketCapture, ChunksNeverSentFallBackAtTheFirstFrame) {
  ScriptedCamera camera;
  camera.chunks = true;
  camera.chunk_triggers = 0;
  BracketCapture capture(camera, FastOptions());
  const BracketResult result = capture.Capture([&](int) { camera.SoftwareTrigger(); });
  ASSERT_TRUE(result.complete) << result.BriefReport();
  for (const BracketFrame& frame : result.frames) EXPECT_FALSE(frame.exposure_from_chunk);
  EXPECT_NE(capture.stats().exposure_notice.find("no frame carried one"), std::string::npos)
      << capture.stats().exposure_notice;
}

// exposure_check: chunk keeps the chunk as the only evidence: a frame without it is rejected, and
// the message names the chunk (never another application).
TEST(BracketCapture, ExposureCheckChunkRejectsFramesWithoutItAndNamesTheChunk) {
  ScriptedCamera camera;
  camera.chunks = true;
  camera.chunk_triggers = 1;
  camera.check = ExposureCheck::kChunk;
  BracketCapture capture(camera, FastOptions());
  const BracketResult result = capture.Capture([&](int) { camera.SoftwareTrigger(); });
  ASSERT_FALSE(result.complete);
  EXPECT_EQ(result.frames.size(), 1u);
  EXPECT_NE(result.failure.find("without their ChunkExposureTime chunk"), std::string::npos)
      << result.failure;
  EXPECT_NE(result.failure.find("camera.exposure_check: readback"), std::string::npos);
  EXPECT_EQ(result.failure.find("application"), std::string::npos) << result.failure;
  EXPECT_TRUE(capture.stats().exposure_notice.empty());
}

// exposure_check: none takes each exposure as written: a camera reporting another value (here a
// chunk twice the exposure) still delivers, nothing retried.
TEST(BracketCapture, ExposureCheckNoneTakesTheExposureAsWritten) {
  ScriptedCamera camera;
  camera.chunks = true;
  camera.check = ExposureCheck::kNone;
  camera.script.assign(5, ScriptedCamera::Act::kWrongChunk);
  BracketCapture capture(camera, FastOptions());
  const BracketResult result = capture.Capture([&](int) { camera.SoftwareTrigger(); });
  ASSERT_TRUE(result.complete) << result.BriefReport();
  EXPECT_EQ(capture.stats().retried, 0);
  for (const BracketFrame& frame : result.frames) {
    EXPECT_FALSE(frame.exposure_from_chunk);
    EXPECT_DOUBLE_EQ(frame.actual_exposure_us, frame.requested_exposure_us);
  }
}

TEST(BracketCapture, ChunkExposureMismatchIsRetried) {
  using Act = ScriptedCamera::Act;
  ScriptedCamera camera;
  camera.chunks = true;
  camera.script = {Act::kWrongChunk};
  BracketCapture capture(camera, FastOptions());
  const BracketResult result = capture.Capture([&](int) { camera.SoftwareTrigger(); });
  ASSERT_TRUE(result.complete);
  EXPECT_EQ(result.frames[0].retries, 1);
  EXPECT_TRUE(result.frames[0].exposure_from_chunk);
  EXPECT_EQ(capture.stats().wrong_exposure, 1);
}

// A camera with a sensor that is busy from a frame's start until the host has its frame: a trigger
// while busy waits, and the frame it starts latches the exposure register when the sensor frees
// (as the virtual camera and cameras with TriggerOverlap ReadOut do). Frames carry exposure chunks;
// `drop` names the triggers (0-based) whose frame never arrives.
class BusySensorCamera : public ScriptedCamera {
 public:
  std::vector<int> drop;
  int triggers = 0;
  int triggers_while_busy = 0;

  double SetExposureUs(double exposure_us) override { return register_us_ = exposure_us; }
  double ExposureUs() override { return register_us_; }
  bool HasExposureChunks() const override { return true; }
  void SoftwareTrigger() override {
    const int index = triggers++;
    if (in_progress_) {
      ++triggers_while_busy;
      waiting_.push_back(index);
    } else {
      Start(index);
    }
  }
  std::optional<RawFrame> WaitFrame(std::chrono::milliseconds) override {
    if (!in_progress_) return std::nullopt;
    std::optional<RawFrame> frame = std::move(in_progress_);
    in_progress_.reset();
    if (!waiting_.empty()) {  // the sensor frees: the waiting trigger starts its frame
      Start(waiting_.front());
      waiting_.pop_front();
    }
    if (frame->status == FrameStatus::kTimeout) return std::nullopt;  // dropped
    return frame;
  }

 private:
  void Start(int index) {
    RawFrame frame;
    const bool dropped = std::find(drop.begin(), drop.end(), index) != drop.end();
    frame.status = dropped ? FrameStatus::kTimeout : FrameStatus::kOk;
    frame.image = cv::Mat(4, 4, CV_16UC1, cv::Scalar(register_us_ / 100.0));
    frame.chunk_exposure_us = register_us_;
    frame.frame_id = static_cast<std::uint64_t>(index + 1);
    frame.timestamp_ns = static_cast<std::uint64_t>(index + 1) * 1000;
    in_progress_ = frame;
  }
  double register_us_ = 1000.0;
  std::optional<RawFrame> in_progress_;
  std::deque<int> waiting_;
};

// A camera whose first `late` triggers reach the sensor late: after the host has written the
// next frame's exposure (a loaded host, a trigger sent through a slow station), so their frames
// latch the exposure register as it is when the host waits for them. Frames carry chunks.
class LateTriggerCamera : public ScriptedCamera {
 public:
  int late = 0;
  int triggers = 0;

  LateTriggerCamera() { chunks = true; }
  void SoftwareTrigger() override {
    if (++triggers > late) {
      ScriptedCamera::SoftwareTrigger();
    } else {
      ++pending_;
    }
  }
  std::optional<RawFrame> WaitFrame(std::chrono::milliseconds timeout) override {
    for (; pending_ > 0; --pending_) ScriptedCamera::SoftwareTrigger();
    return ScriptedCamera::WaitFrame(timeout);
  }

 private:
  int pending_ = 0;
};

// Three late triggers: the pipelined write of the successor's exposure lands before each. A
// retry is taken without that write (and the successor's exposure programmed after it), so each
// frame hit needs one retry and the bracket completes with every frame at its own exposure
// (before: the reference was taken three times at 30000 us and the bracket failed, as the
// sanitized CI's virtual rig showed under load).
TEST(BracketCapture, ARetryAfterALateTriggerIsNotPipelined) {
  LateTriggerCamera camera;
  camera.late = 3;  // frame 0's first try and its retry; frame 1's first try
  BracketCapture capture(camera, FastOptions());
  const BracketResult result = capture.Capture([&](int) { camera.SoftwareTrigger(); });
  ASSERT_TRUE(result.complete) << result.BriefReport();
  EXPECT_EQ(result.frames[0].retries, 1);
  EXPECT_EQ(result.frames[1].retries, 1);
  EXPECT_EQ(capture.stats().wrong_exposure, 2);
  for (size_t i = 0; i < result.frames.size(); ++i) {
    EXPECT_DOUBLE_EQ(result.frames[i].actual_exposure_us, FastOptions().exposures_us[i]) << i;
  }
}

BracketOptions InReadoutOptions() {
  BracketOptions options = FastOptions();
  options.pipeline_margin = std::chrono::microseconds(0);
  options.exposures_us = {80.0, 300.0, 320.0, 340.0, 360.0};  // short: the test sleeps through them
  options.trigger_in_readout = true;
  return options;
}

// Each frame's exposure as the image says it was taken (the camera paints exposure / 100).
void ExpectFramesCarryTheirExposures(const BracketResult& result, const BracketOptions& options) {
  ASSERT_TRUE(result.complete) << result.BriefReport();
  ASSERT_EQ(result.frames.size(), options.exposures_us.size());
  for (size_t i = 0; i < result.frames.size(); ++i) {
    EXPECT_DOUBLE_EQ(result.frames[i].actual_exposure_us, options.exposures_us[i]) << i;
    EXPECT_NEAR(result.frames[i].image.at<std::uint16_t>(0, 0), options.exposures_us[i] / 100.0,
                0.5)
        << "frame " << i;
  }
}

TEST(BracketCapture, InReadoutTheNextTriggerFiresBeforeTheFrameArrives) {
  BusySensorCamera camera;
  const BracketOptions options = InReadoutOptions();
  BracketCapture capture(camera, options);
  int fired = 0;
  std::vector<int> fired_when_seen;
  const BracketResult result = capture.Capture(
      [&](int) {
        ++fired;
        camera.SoftwareTrigger();
      },
      [&](const BracketFrame&) { fired_when_seen.push_back(fired); });
  ExpectFramesCarryTheirExposures(result, options);
  EXPECT_EQ(fired_when_seen, (std::vector<int>{2, 3, 4, 5, 5}));
  EXPECT_EQ(camera.triggers_while_busy, 4);
  EXPECT_EQ(capture.stats().fired_in_readout, 4);
  EXPECT_EQ(capture.stats().lost, 0);
}

TEST(BracketCapture, InReadoutAFailedFrameNeverTakesItsSuccessorsFrame) {
  for (int dropped = 0; dropped < 4; ++dropped) {
    BusySensorCamera camera;
    camera.drop = {dropped};
    const BracketOptions options = InReadoutOptions();
    BracketCapture capture(camera, options);
    const BracketResult result = capture.Capture([&](int) { camera.SoftwareTrigger(); });
    ExpectFramesCarryTheirExposures(result, options);
    EXPECT_EQ(result.frames[static_cast<size_t>(dropped)].retries, 1) << "dropped " << dropped;
    EXPECT_EQ(capture.stats().late, 1) << capture.stats().BriefReport();
    EXPECT_EQ(capture.stats().wrong_exposure, 0) << capture.stats().BriefReport();
  }
}

TEST(BracketCapture, InReadoutEqualNeighbourExposuresAreTriggeredInTurn) {
  BusySensorCamera camera;
  BracketOptions options = InReadoutOptions();
  options.exposures_us = {80.0, 300.0, 300.0, 340.0};
  BracketCapture capture(camera, options);
  const BracketResult result = capture.Capture([&](int) { camera.SoftwareTrigger(); });
  ExpectFramesCarryTheirExposures(result, options);
  EXPECT_EQ(capture.stats().fired_in_readout, 2);  // not between the two equal exposures
}

TEST(BracketCapture, DuringLastReadoutRunsOnceAfterTheLastTriggerBeforeItsFrameIsSeen) {
  for (const bool in_readout : {false, true}) {
    BusySensorCamera camera;
    BracketOptions options = InReadoutOptions();
    options.trigger_in_readout = in_readout;
    BracketCapture capture(camera, options);
    int seen = 0, calls = 0, seen_at_call = -1, fired_at_call = -1;
    const BracketResult result = capture.Capture(
        [&](int) { camera.SoftwareTrigger(); }, [&](const BracketFrame&) { ++seen; },
        [&] {
          ++calls;
          seen_at_call = seen;
          fired_at_call = camera.triggers;
        });
    ExpectFramesCarryTheirExposures(result, options);
    EXPECT_EQ(calls, 1);
    EXPECT_EQ(seen_at_call, 4) << "the last frame is not handed over yet";
    EXPECT_EQ(fired_at_call, 5) << "every trigger fired";
  }
}

// The fake camera's Mono8 pattern: pixel (x, y) = ((x + frame_id + y) % 255) * s with
// s = 1 + log10(exposure_us / 10000). Reads the exposure back from the pixel whose base value is 200.
double ExposureFromFakePattern(const BracketFrame& frame) {
  const int x = static_cast<int>((200 + 255 - frame.frame_id % 255) % 255);
  const double value = frame.image.at<std::uint16_t>(0, x);
  return 10000.0 * std::pow(10.0, value / 200.0 - 1.0);
}

TEST(BracketCapture, FakeGigECameraFramesCarryTheRequestedExposuresInOrder) {
  testing::FakeCameraProcess fake("IRDBRK01");
  auto camera = AravisCamera::Open("127.0.0.1", fake.serial());
  CameraSettings settings;
  settings.pixel_format = "Mono8";
  settings.trigger_source = "Software";
  settings.width = 512;
  settings.height = 64;
  camera->Configure(settings);
  BracketOptions options;
  options.exposures_us = {10000.0, 3000.0, 5000.0, 8000.0, 14000.0};
  options.trigger_source = "Software";
  BracketCapture capture(*camera, options);
  for (int repeat = 0; repeat < 2; ++repeat) {
    const BracketResult result = capture.Capture([&](int) { camera->SoftwareTrigger(); });
    ASSERT_TRUE(result.complete) << result.BriefReport() << " / " << capture.stats().BriefReport();
    ASSERT_EQ(result.frames.size(), 5u);
    for (size_t i = 0; i < 5; ++i) {
      const BracketFrame& frame = result.frames[i];
      EXPECT_NEAR(frame.actual_exposure_us, options.exposures_us[i], 1.0);
      EXPECT_NEAR(ExposureFromFakePattern(frame), options.exposures_us[i],
                  0.02 * options.exposures_us[i])
          << "frame " << i << " of bracket " << repeat;
      if (i > 0) {
        EXPECT_GT(frame.timestamp_ns, result.frames[i - 1].timestamp_ns);
      }
    }
  }
  camera->StopStream();
  EXPECT_EQ(capture.stats().lost, 0) << capture.stats().BriefReport();
  EXPECT_EQ(capture.stats().received, 10);
}

}  // namespace
}  // namespace irdist
