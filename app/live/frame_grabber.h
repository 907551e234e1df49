#pragma once
// The camera running continuously at one exposure for `irdist measure --track`: a thread fires the
// frame trigger `ahead` frames in advance (so the sensor never waits for the host: frames follow
// each other at exposure + readout, the highest rate the ROI allows when triggered), takes each
// frame from the stream and keeps only the newest for the estimator (Take). Nothing is dropped
// silently: a frame replaced before the estimator took it is counted `skipped`, a triggered frame
// that never came (a gap in the frame ids, or nothing until the frame timeout) or came damaged
// `lost`, one taken with another exposure `wrong_exposure`.
// Latency stays one estimate: the estimator always takes the newest frame, never a queue.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <functional>
#include <mutex>
#include <optional>
#include <thread>

#include "acquisition/camera.h"

namespace irdist {

// What happened to the frames so far (cumulative over the run).
struct TrackCounters {
  std::int64_t triggered = 0;       // frame triggers fired (warm-ups excluded)
  std::int64_t received = 0;        // frames delivered whole at the track's exposure
  std::int64_t estimated = 0;       // of which the estimator took
  std::int64_t skipped = 0;         // replaced by a newer frame before the estimator took them
  std::int64_t lost = 0;            // triggered and never delivered, or delivered damaged
  std::int64_t wrong_exposure = 0;  // delivered with another exposure than the track's
  // Received as the grabbing stopped (the run's end, or before a bracket check): the frames then
  // in flight, and the one waiting for the estimator.
  std::int64_t drained = 0;
};

struct GrabberOptions {
  double exposure_us = 8000.0;
  int ahead = 2;  // triggers in flight (1: fire after each frame arrived)
  std::chrono::milliseconds frame_timeout{1000};
  // Relative tolerance of a frame's ChunkExposureTime against exposure_us.
  double exposure_tolerance = 0.01;
  // The first problem, naming the field, in *why (empty when valid).
  bool IsValid(std::string* why) const;
};

// A frame handed to the estimator, with its number among the frames received (from 0) and the
// counters as it was taken (its own skipped frames, those numbered before it, all counted).
struct GrabbedFrame {
  RawFrame raw;
  std::int64_t number = 0;
  TrackCounters counters;
};

class FrameGrabber {
 public:
  using Trigger = std::function<void(int)>;
  // `camera` (configured, triggered) and `trigger` must outlive the grabber.
  FrameGrabber(Camera& camera, Trigger trigger, const GrabberOptions& options);
  ~FrameGrabber();  // stops the thread (Stop)
  FrameGrabber(const FrameGrabber&) = delete;
  FrameGrabber& operator=(const FrameGrabber&) = delete;

  // Sets the exposure, starts the stream where it is not running (one warm-up frame fired and
  // discarded, as a bracket's) and the grabbing thread. Throws CameraError.
  void Start();
  // Fires no more triggers, waits for those in flight (each up to the frame timeout) and joins
  // the thread; those frames and one still waiting for the estimator are counted drained.
  // Rethrows the thread's CameraError, if any.
  void Stop();
  // The newest frame not yet taken, waiting up to `timeout`; std::nullopt when none came.
  std::optional<GrabbedFrame> Take(std::chrono::milliseconds timeout);
  TrackCounters counters() const;

 private:
  void Loop();
  // One frame from the stream (or its absence), accounted for; false once the thread must end.
  bool Receive(int* in_flight);
  void Fire(int* in_flight);

  Camera& camera_;
  Trigger trigger_;
  GrabberOptions options_;
  mutable std::mutex mutex_;
  std::condition_variable arrived_;
  std::optional<GrabbedFrame> newest_;
  TrackCounters counters_;
  std::int64_t next_number_ = 0;
  std::uint64_t last_id_ = 0;  // the last whole frame's id (0: none since Start)
  std::atomic<bool> stopping_{false};
  std::exception_ptr failure_;
  std::thread thread_;
};

}  // namespace irdist
