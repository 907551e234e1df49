#pragma once
// Bracketed capture: one frame at the reference exposure t_r and one at each measurement exposure
// t_n, of one pose and one IRED current. The trigger is a callable the caller hands in (the
// station's trigger output in a sweep, a software trigger in tests): acquisition never knows the
// station.
//
// Per frame: fire the trigger, wait for the frame, match it to the request (frame id strictly newer
// than the last one seen, 16-bit wrap aware, and a later camera timestamp), verify the exposure it
// was taken with, and retry a missing, damaged or wrong-exposure frame up to max_retries.
//
// The exposure is latched when the camera starts a frame. Two ways to program the next one:
// - pipelined (the camera sends ChunkExposureTime and options.pipelined): exposure N+1 is written
//   while frame N is read out, right after frame N's exposure ends (its trigger + exposure time +
//   pipeline_margin), without a read-back; the frame's own chunk says what it was taken with, so a
//   write that came late or early makes a wrong-exposure frame that is retried, never a mislabelled
//   one. The per-frame cost beyond exposure + readout is the trigger and the transfer.
//   With trigger_in_readout (a camera that takes a trigger during readout: GenICam TriggerOverlap
//   ReadOut, or one that queues it), frame N+1 is triggered right after its exposure is written,
//   still in frame N's readout, so it starts as the sensor frees: the trigger latency and the
//   transfer leave the frame period too. A frame N that fails then waits for N+1's frame and
//   discards it before the retry; each frame is still checked against its own chunk. A retry is
//   taken serially (its exposure read back, no write of N+1's during it; N+1's programmed after
//   it): a trigger that reached the sensor after that write (a loaded host, a slow trigger path)
//   would latch N+1's exposure on every pipelined retry.
// - the exposure evidence follows the camera's exposure_check (camera.h ExposureCheck): by default
//   the chunk while frames carry it; the first frame without it (chunks never sent, or stopped
//   mid-run) turns the capture serial with read-backs for good, said once (options.on_notice,
//   stats().exposure_notice), and that frame is retaken (no retry spent): good frames are never
//   rejected for a missing chunk. With exposure_check chunk, a frame without one is rejected.
// - serial (no chunks): exposure N+1 is written after frame N has arrived and read back until the
//   camera reports it (a camera may apply a write late), then the trigger fires; the read-back is
//   the frame's exposure.

#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "acquisition/camera.h"

namespace irdist {

struct BracketOptions {
  // Reference exposure first, then the measurement exposures, in trigger order.
  std::vector<double> exposures_us = {8000.0, 30000.0, 32000.0, 34000.0, 36000.0};
  std::string trigger_source = "Line1";        // the camera input wired to the station
  std::chrono::milliseconds frame_timeout{1000};
  int max_retries = 2;                         // per frame, before the sweep stops
  // Drift control: retake t_r next to each t_n (trigger order r, n1, r, n2, r, n3, ...).
  bool interleave_reference = false;
  // Relative difference allowed between requested and actual exposure.
  double exposure_tolerance = 0.005;
  // After a frame timed out, frames arriving within this window are late leftovers: they are
  // discarded (counted) before the retry is triggered.
  std::chrono::milliseconds late_frame_window{150};
  // When Capture() starts the stream and the trigger is not Software, fire trigger(-1) once and
  // discard its frame: Aravis sizes the socket buffer on the first packet, so the first frame
  // after AcquisitionStart may come incomplete. The trigger callable must accept -1.
  bool warmup_trigger = true;
  // Program the next exposure during the current frame's readout when the camera sends exposure
  // chunks (see above); false = always serial.
  bool pipelined = true;
  // Time after trigger + exposure before the next exposure is written (covers the trigger latency).
  std::chrono::microseconds pipeline_margin{500};
  // Pipelined only: the camera accepts a trigger while it reads the previous frame out (see above).
  // The rig file's camera.trigger_in_readout. false = trigger after the frame arrived.
  bool trigger_in_readout = false;
  // Serial mode: how long a written exposure may take to read back before it is a CameraError.
  std::chrono::milliseconds exposure_settle_timeout{500};
  // Called once when the exposure evidence falls back from the chunk to the read-back (with why),
  // for the command to print; the text is also kept in CaptureStats::exposure_notice.
  std::function<void(const std::string&)> on_notice;
  bool IsValid(std::string* why) const;
};

enum class FrameRole { kReference, kMeasurement };
const char* FrameRoleName(FrameRole role);  // "ref" / "meas" (the recording's spelling)

// One planned frame of a bracket.
struct PlannedFrame {
  int frame_in_bracket = 0;
  int exposure_index = 0;  // into BracketOptions::exposures_us
  FrameRole role = FrameRole::kReference;
  double exposure_us = 0.0;
};
// The trigger order for `options` (with interleaving applied).
std::vector<PlannedFrame> PlanBracket(const BracketOptions& options);

struct BracketFrame {
  PlannedFrame plan;
  cv::Mat image;                    // CV_16UC1, values as delivered
  int bit_depth = 16;
  double requested_exposure_us = 0.0;
  double actual_exposure_us = 0.0;
  bool exposure_from_chunk = false; // else: read back before the trigger
  std::uint64_t frame_id = 0;
  std::uint64_t timestamp_ns = 0;
  std::int64_t host_time_ns = 0;
  std::int64_t host_monotonic_ns = 0;
  int retries = 0;                  // retries this frame needed
  FrameStatus status = FrameStatus::kOk;
};

struct BracketResult {
  std::vector<BracketFrame> frames;  // in trigger order; all kOk when complete
  bool complete = false;
  std::string failure;               // why not complete
  std::string BriefReport() const;
};

// Everything counted over the life of a BracketCapture.
struct CaptureStats {
  std::int64_t brackets = 0;           // Capture() calls
  std::int64_t brackets_failed = 0;    // brackets given up
  std::int64_t requested = 0;          // frames planned
  std::int64_t received = 0;           // frames delivered and accepted
  std::int64_t retried = 0;            // extra triggers fired
  std::int64_t lost = 0;               // frames given up after max_retries
  std::int64_t timeouts = 0;           // attempts that saw nothing in time (no buffer at all)
  std::int64_t damaged = 0;            // attempts whose frame came incomplete (a failed buffer)
  std::int64_t wrong_exposure = 0;     // attempts whose frame carried another exposure
  std::int64_t duplicates = 0;         // buffers discarded as stale or repeated (id/timestamp)
  std::int64_t late = 0;               // frames that arrived after their attempt timed out
  std::int64_t stray = 0;              // frames queued before a bracket (no trigger of ours)
  std::int64_t id_gaps = 0;            // frame ids skipped by the camera
  std::int64_t warmup = 0;             // warm-up frames fired and discarded
  std::int64_t pipelined_frames = 0;   // frames whose successor's exposure was written in readout
  std::int64_t fired_in_readout = 0;   // triggers fired during the previous frame's readout
  std::int64_t exposure_rereads = 0;   // read-backs that still showed the old value
  std::int64_t without_chunk = 0;      // frames that came without the chunk they were to carry
  std::string exposure_notice;         // the chunk-to-read-back fallback, when it happened
  // Failed buffers the stream handed back, by FrameStatusName (missing_packets, timeout, ...).
  // A failed buffer's frame id and timestamp are not trusted (a lost leader packet leaves them 0
  // or stale): they never move the frame identity that tells duplicates apart.
  std::map<std::string, std::int64_t> failed_buffers;
  TransferStats transfer;              // the camera's packet counters (resends, missing packets)
  std::string BriefReport() const;
};

class BracketCapture {
 public:
  using Trigger = std::function<void(int frame_in_bracket)>;

  // `camera` must be configured (triggered) and must outlive this object.
  BracketCapture(Camera& camera, BracketOptions options);

  // Captures one bracket, starting the camera's stream if needed. A frame still missing after
  // max_retries ends the bracket with complete == false (the caller decides to stop the sweep).
  // Camera failures (clamped exposure, dead link) throw CameraError; exceptions from `trigger`
  // propagate.
  // `on_frame`, when given, sees each frame as soon as it is accepted, before the next one is
  // triggered (so it must return quickly: e.g. hand the frame to a worker that stores it while the
  // next one is exposed). Frames of a bracket that ends incomplete are seen too.
  using FrameSink = std::function<void(const BracketFrame& frame)>;
  // `during_last_readout`, when given, runs once the last frame's exposure has ended, while it is
  // read out (again if that frame is retaken): host work that needs the bracket's light to be
  // over (the IRED current's read-back) costs no time there. Its exceptions propagate.
  BracketResult Capture(const Trigger& trigger, const FrameSink& on_frame = {},
                        std::function<void()> during_last_readout = {});

  const BracketOptions& options() const { return options_; }
  const CaptureStats& stats() const { return stats_; }

 private:
  enum class Outcome { kOk, kTimeout, kDamaged, kWrongExposure, kNoChunk };
  // The outcomes of one planned frame's attempts, for the message when it is given up.
  struct AttemptLog {
    int timeouts = 0;
    int damaged = 0;
    int wrong_exposure = 0;
    int no_chunk = 0;
    double last_exposure_us = 0.0;  // the last wrong exposure's evidence, and whether a chunk's
    bool last_from_chunk = false;
  };
  // Whether frames are checked against their chunk now (exposure_check auto or chunk, the camera
  // sends chunks, and they have not stopped).
  bool ChunkEvidence() const;
  // A frame came without its chunk: under exposure_check auto, the read-back from now on.
  void FallBackToReadback(const PlannedFrame& plan);
  void PrepareStream(const Trigger& trigger);
  bool Pipelining() const;
  // Writes `exposure_us` and reads it back until the camera reports it; returns the read-back.
  double ProgramExposure(double exposure_us);
  // Takes `plan` with retries; `next` (or null) is the exposure to program during its readout.
  bool TakeFrame(const PlannedFrame& plan, const PlannedFrame* next, const Trigger& trigger,
                 BracketFrame* frame, bool* next_programmed, AttemptLog* log);
  Outcome Attempt(const PlannedFrame& plan, double readback_us, const Trigger& trigger,
                  const PlannedFrame* next, BracketFrame* out);
  // Fires `plan`'s trigger unless it was fired during the previous frame's readout; returns a
  // time no earlier than the frame's start.
  std::chrono::steady_clock::time_point StartFrame(const PlannedFrame& plan,
                                                   const Trigger& trigger);
  // Whether `next` may be triggered during `plan`'s readout (its frame is told apart by its chunk).
  bool FiresAhead(const PlannedFrame& plan, const PlannedFrame& next) const;
  // Waits for the frame of `next`'s trigger fired in a failed frame's readout and discards it.
  void DiscardFrameFiredAhead(const PlannedFrame& next);
  Outcome AwaitFrame(const PlannedFrame& plan, double readback_us,
                     std::chrono::steady_clock::time_point deadline, BracketFrame* out);
  // The exposure evidence of an accepted frame (its chunk or `readback_us`, NaN when pipelined)
  // against `plan`'s.
  Outcome JudgeExposure(const PlannedFrame& plan, double readback_us,
                        const std::optional<double>& chunk_us, BracketFrame* out);
  void CountFailure(Outcome outcome, BracketFrame* frame, AttemptLog* log);
  void CountFailedBuffer(FrameStatus status);
  // Why `plan` was given up: the network first when packets were lost (incomplete buffers, or
  // packets missing or asked again since `before`), the trigger when nothing arrived.
  std::string FailureText(const PlannedFrame& plan, const AttemptLog& log,
                          const TransferStats& before) const;
  bool AcceptId(std::uint64_t frame_id, std::uint64_t timestamp_ns);
  void DrainLateFrames();
  // A frame that is no attempt's: a failed buffer (by status), late (a newer id) or a duplicate.
  void CountLeftover(const RawFrame& frame);

  Camera& camera_;
  BracketOptions options_;
  CaptureStats stats_;
  bool have_last_ = false;
  std::uint64_t last_id_ = 0;
  std::uint64_t last_timestamp_ns_ = 0;
  // Set when the frame just taken had its successor's trigger fired in its readout: a time no
  // earlier than the successor's start (the later of that trigger and the frame's arrival).
  std::optional<std::chrono::steady_clock::time_point> started_ahead_;
  std::function<void()> during_last_readout_;  // of the Capture() in progress
  bool chunks_lost_ = false;                   // the chunks stopped: read-backs for good
  std::int64_t frames_with_chunk_ = 0;
  int last_frame_ = -1;                        // frame_in_bracket of its last frame
};

}  // namespace irdist
