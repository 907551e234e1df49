#include "app/live/frame_grabber.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <string>
#include <utility>

#include "base/bounds.h"

namespace irdist {

namespace {

// Frames skipped between two frame ids: GigE Vision 1.x block ids count 1..65535 and wrap to 1;
// 0 = unknown (the first frame, or a camera without ids).
std::int64_t IdGap(std::uint64_t last, std::uint64_t id) {
  if (last == 0 || id == 0) return 0;
  if (id > last) return static_cast<std::int64_t>(id - last - 1);
  return last <= 0xffff ? static_cast<std::int64_t>(0xffff - last + id - 1) : 0;
}

// More triggers in flight than any camera queues (the virtual one and readout overlap need 2).
constexpr int kMostAhead = 16;

}  // namespace

bool GrabberOptions::IsValid(std::string* why) const {
  std::string reason = bounds::kExposureUs.Refusal("exposure_us", exposure_us);
  if (reason.empty() && (ahead < 1 || ahead > kMostAhead)) {
    reason = "ahead = " + std::to_string(ahead) + " is outside [1, " + std::to_string(kMostAhead) +
             "] triggers in flight";
  }
  if (reason.empty() && frame_timeout.count() <= 0) reason = "frame_timeout must be positive";
  if (reason.empty() && !(exposure_tolerance > 0.0 && exposure_tolerance < 1.0)) {
    reason = "exposure_tolerance not in (0, 1)";
  }
  if (why != nullptr) *why = reason;
  return reason.empty();
}

FrameGrabber::FrameGrabber(Camera& camera, Trigger trigger, const GrabberOptions& options)
    : camera_(camera), trigger_(std::move(trigger)), options_(options) {
  std::string why;
  IRDIST_CHECK(options_.IsValid(&why), "GrabberOptions: " + why);
}

FrameGrabber::~FrameGrabber() {
  stopping_ = true;
  if (thread_.joinable()) thread_.join();
}

void FrameGrabber::Start() {
  IRDIST_CHECK(!thread_.joinable(), "FrameGrabber::Start() while running");
  camera_.SetExposureUs(options_.exposure_us);
  if (!camera_.streaming()) {
    camera_.StartStream();
    // The first frame after AcquisitionStart may come incomplete (the stream sizes its socket
    // buffer on it): one warm-up frame, discarded, as a bracket's warm-up trigger.
    trigger_(-1);
    camera_.WaitFrame(options_.frame_timeout);
  }
  camera_.Flush();  // frames of before (a bracket's), none of this track's
  stopping_ = false;
  failure_ = nullptr;
  last_id_ = 0;  // a bracket's frames took ids in between
  thread_ = std::thread([this] { Loop(); });
}

void FrameGrabber::Stop() {
  stopping_ = true;
  if (thread_.joinable()) thread_.join();
  std::lock_guard<std::mutex> lock(mutex_);
  if (newest_) ++counters_.drained;
  newest_.reset();
  if (failure_) std::rethrow_exception(failure_);
}

void FrameGrabber::Loop() {
  try {
    int in_flight = 0;
    while (!stopping_) {
      while (in_flight < options_.ahead) Fire(&in_flight);
      Receive(&in_flight);
    }
    while (in_flight > 0) Receive(&in_flight);  // the frames already triggered
  } catch (...) {
    std::lock_guard<std::mutex> lock(mutex_);
    failure_ = std::current_exception();
  }
  arrived_.notify_all();
}

void FrameGrabber::Fire(int* in_flight) {
  trigger_(0);
  ++*in_flight;
  std::lock_guard<std::mutex> lock(mutex_);
  ++counters_.triggered;
}

bool FrameGrabber::Receive(int* in_flight) {
  std::optional<RawFrame> frame = camera_.WaitFrame(options_.frame_timeout);
  std::lock_guard<std::mutex> lock(mutex_);
  if (!frame) {  // nothing within a frame's time: every frame in flight is lost
    counters_.lost += *in_flight;
    *in_flight = 0;
    return false;
  }
  *in_flight = std::max(0, *in_flight - 1);
  if (frame->status != FrameStatus::kOk || frame->image.empty()) {
    ++counters_.lost;
    last_id_ = 0;  // a failed buffer's id is not trusted: the next gap is unknown
    return false;
  }
  // Frames the camera numbered but never sent (their triggers were in flight): lost now, not at
  // the next timeout.
  const int gap =
      static_cast<int>(std::min<std::int64_t>(IdGap(last_id_, frame->frame_id), *in_flight));
  counters_.lost += gap;
  *in_flight -= gap;
  last_id_ = frame->frame_id;
  if (frame->chunk_exposure_us && std::abs(*frame->chunk_exposure_us / options_.exposure_us - 1.0) >
                                      options_.exposure_tolerance) {
    ++counters_.wrong_exposure;
    return false;
  }
  ++counters_.received;
  if (stopping_) {  // in flight as the grabbing stopped: no estimator waits for it
    ++counters_.drained;
    return true;
  }
  if (newest_) ++counters_.skipped;
  newest_ = GrabbedFrame{std::move(*frame), next_number_++, {}};
  arrived_.notify_one();
  return true;
}

std::optional<GrabbedFrame> FrameGrabber::Take(std::chrono::milliseconds timeout) {
  std::unique_lock<std::mutex> lock(mutex_);
  arrived_.wait_for(lock, timeout, [this] { return newest_.has_value() || failure_; });
  if (failure_ && !newest_) std::rethrow_exception(failure_);
  std::optional<GrabbedFrame> taken = std::move(newest_);
  newest_.reset();
  if (taken) {
    ++counters_.estimated;
    taken->counters = counters_;
  }
  return taken;
}

TrackCounters FrameGrabber::counters() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return counters_;
}

}  // namespace irdist
