#include "acquisition/bracket.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <thread>
#include <sstream>
#include <utility>

namespace irdist {

bool BracketOptions::IsValid(std::string* why) const {
  auto fail = [why](const std::string& message) {
    if (why != nullptr) *why = message;
    return false;
  };
  if (exposures_us.size() < 2) {
    return fail("exposures_us needs the reference exposure and at least one measurement exposure");
  }
  for (double exposure : exposures_us) {
    if (!(exposure > 0.0) || !std::isfinite(exposure)) {
      return fail("every exposure must be a positive number of microseconds");
    }
  }
  if (trigger_source.empty()) return fail("trigger_source is empty");
  if (frame_timeout.count() <= 0) return fail("frame_timeout must be > 0");
  if (max_retries < 0) return fail("max_retries must be >= 0");
  if (!(exposure_tolerance >= 0.0 && exposure_tolerance < 0.5)) {
    return fail("exposure_tolerance must be in [0, 0.5)");
  }
  if (late_frame_window.count() < 0) return fail("late_frame_window must be >= 0");
  if (pipeline_margin.count() < 0) return fail("pipeline_margin must be >= 0");
  if (exposure_settle_timeout.count() < 0) return fail("exposure_settle_timeout must be >= 0");
  return true;
}

const char* FrameRoleName(FrameRole role) {
  switch (role) {
    case FrameRole::kReference:
      return "ref";
    case FrameRole::kMeasurement:
      return "meas";
  }
  return "meas";
}

std::vector<PlannedFrame> PlanBracket(const BracketOptions& options) {
  std::vector<PlannedFrame> plan;
  auto add = [&](int exposure_index) {
    PlannedFrame frame;
    frame.frame_in_bracket = static_cast<int>(plan.size());
    frame.exposure_index = exposure_index;
    frame.role = exposure_index == 0 ? FrameRole::kReference : FrameRole::kMeasurement;
    frame.exposure_us = options.exposures_us[static_cast<size_t>(exposure_index)];
    plan.push_back(frame);
  };
  const int count = static_cast<int>(options.exposures_us.size());
  if (!options.interleave_reference) {
    for (int i = 0; i < count; ++i) add(i);
  } else {
    for (int i = 1; i < count; ++i) {
      add(0);
      add(i);
    }
  }
  return plan;
}

std::string BracketResult::BriefReport() const {
  std::ostringstream out;
  out << (complete ? "complete" : "incomplete") << " bracket, " << frames.size() << " frames";
  int retries = 0;
  for (const auto& frame : frames) retries += frame.retries;
  if (retries > 0) out << ", " << retries << " retries";
  if (!complete && !failure.empty()) out << ": " << failure;
  return out.str();
}

std::string CaptureStats::BriefReport() const {
  std::ostringstream out;
  out << "brackets " << brackets << " (failed " << brackets_failed << "), frames requested "
      << requested << ", received " << received << ", retried " << retried << ", lost " << lost
      << " [timeouts " << timeouts << ", damaged " << damaged << ", wrong exposure "
      << wrong_exposure << ", duplicates " << duplicates << ", late " << late << ", stray "
      << stray << ", id gaps " << id_gaps << ", warm-up " << warmup << ", pipelined "
      << pipelined_frames << ", fired in readout " << fired_in_readout << ", exposure re-reads "
      << exposure_rereads << ", without chunk " << without_chunk << "], packets resent "
      << transfer.resent_packets << " of " << transfer.resend_requests << " asked, missing "
      << transfer.missing_packets;
  if (!failed_buffers.empty()) {
    out << ", failed buffers:";
    for (const auto& [status, count] : failed_buffers) out << " " << status << " " << count;
  }
  if (!exposure_notice.empty()) out << "; " << exposure_notice;
  return out.str();
}

BracketCapture::BracketCapture(Camera& camera, BracketOptions options)
    : camera_(camera), options_(std::move(options)) {
  std::string why;
  IRDIST_CHECK(options_.IsValid(&why), why);
}

bool BracketCapture::AcceptId(std::uint64_t frame_id, std::uint64_t timestamp_ns) {
  if (have_last_) {
    std::uint64_t step = 0;
    if (frame_id > 0xFFFF || last_id_ > 0xFFFF) {  // 64-bit block ids (GigE Vision 2)
      if (frame_id <= last_id_) return false;
      step = frame_id - last_id_;
    } else {  // 16-bit block ids wrap; id 0 is skipped by GigE Vision 1.x cameras
      step = (frame_id - last_id_) & 0xFFFF;
      if (step == 0 || step >= 0x8000) return false;
      if (frame_id < last_id_ && step > 1) --step;
    }
    if (timestamp_ns != 0 && last_timestamp_ns_ != 0 && timestamp_ns <= last_timestamp_ns_) {
      return false;
    }
    if (step > 1) stats_.id_gaps += static_cast<std::int64_t>(step - 1);
  }
  have_last_ = true;
  last_id_ = frame_id;
  last_timestamp_ns_ = timestamp_ns;
  return true;
}

void BracketCapture::DrainLateFrames() {
  const auto end = std::chrono::steady_clock::now() + options_.late_frame_window;
  while (true) {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(end - std::chrono::steady_clock::now());
    if (left.count() <= 0) break;
    auto frame = camera_.WaitFrame(left);
    if (!frame) break;
    CountLeftover(*frame);
  }
}

void BracketCapture::CountFailedBuffer(FrameStatus status) {
  ++stats_.failed_buffers[FrameStatusName(status)];
}

void BracketCapture::CountLeftover(const RawFrame& frame) {
  if (frame.status != FrameStatus::kOk) {
    CountFailedBuffer(frame.status);
  } else if (AcceptId(frame.frame_id, frame.timestamp_ns)) {
    ++stats_.late;
  } else {
    ++stats_.duplicates;
  }
}

bool BracketCapture::ChunkEvidence() const {
  const ExposureCheck check = camera_.exposure_check();
  return (check == ExposureCheck::kAuto || check == ExposureCheck::kChunk) &&
         camera_.HasExposureChunks() && !chunks_lost_;
}

bool BracketCapture::Pipelining() const { return options_.pipelined && ChunkEvidence(); }

void BracketCapture::FallBackToReadback(const PlannedFrame& plan) {
  chunks_lost_ = true;
  std::ostringstream out;
  out << "frame " << plan.frame_in_bracket << " of bracket " << stats_.brackets
      << " came without its ChunkExposureTime chunk (chunk mode is on; "
      << (frames_with_chunk_ == 0 ? "no frame carried one"
                                  : "the chunks stopped after " +
                                        std::to_string(frames_with_chunk_) + " frames")
      << "): each exposure is read back before its trigger from now on (no pipelining). Chunk "
         "data is lost on the way (a NIC or switch), laid out in a way Aravis cannot parse, or "
         "ignored by the firmware for this pixel format; set camera.exposure_check: readback to "
         "say so in the rig file";
  stats_.exposure_notice = out.str();
  if (options_.on_notice) options_.on_notice(stats_.exposure_notice);
}

double BracketCapture::ProgramExposure(double exposure_us) {
  camera_.WriteExposureUs(exposure_us);
  if (camera_.exposure_check() == ExposureCheck::kNone) return exposure_us;  // taken as written
  const auto deadline = std::chrono::steady_clock::now() + options_.exposure_settle_timeout;
  const double tolerance = std::max(options_.exposure_tolerance * exposure_us, 1e-6);
  while (true) {
    const double back = camera_.ExposureUs();
    if (std::fabs(back - exposure_us) <= tolerance) return back;
    if (std::chrono::steady_clock::now() >= deadline) {
      std::ostringstream out;
      out << "exposure " << exposure_us << " us was written but the camera reports " << back
          << " us after " << options_.exposure_settle_timeout.count()
          << " ms (clamped or rounded): use exposures within the camera's range and increments";
      throw CameraError(out.str());
    }
    ++stats_.exposure_rereads;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}

BracketCapture::Outcome BracketCapture::AwaitFrame(const PlannedFrame& plan, double readback_us,
                                                   std::chrono::steady_clock::time_point deadline,
                                                   BracketFrame* out) {
  while (true) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) return Outcome::kTimeout;
    std::optional<RawFrame> frame = camera_.WaitFrame(left);
    if (!frame) return Outcome::kTimeout;
    if (frame->status != FrameStatus::kOk) {
      // Its id and timestamp may be 0 or stale (a lost leader): counted by status, never matched.
      // Some of its packets arrived, even when Aravis calls it a timeout (not completed within
      // the frame retention): an incomplete frame, not a silent trigger.
      CountFailedBuffer(frame->status);
      out->status = frame->status;
      return Outcome::kDamaged;
    }
    if (!AcceptId(frame->frame_id, frame->timestamp_ns)) {
      ++stats_.duplicates;
      continue;
    }
    out->frame_id = frame->frame_id;
    out->timestamp_ns = frame->timestamp_ns;
    out->host_time_ns = frame->host_time_ns;
    out->host_monotonic_ns = frame->host_monotonic_ns;
    out->status = frame->status;
    out->image = std::move(frame->image);
    out->bit_depth = frame->bit_depth;
    return JudgeExposure(plan, readback_us, frame->chunk_exposure_us, out);
  }
}

BracketCapture::Outcome BracketCapture::JudgeExposure(const PlannedFrame& plan,
                                                      double readback_us,
                                                      const std::optional<double>& chunk_us,
                                                      BracketFrame* out) {
  if (ChunkEvidence() && !chunk_us.has_value()) {
    ++stats_.without_chunk;
    out->status = FrameStatus::kWrongExposure;
    if (camera_.exposure_check() == ExposureCheck::kChunk) return Outcome::kNoChunk;
    FallBackToReadback(plan);
    // Pipelined, the read-back says nothing about this frame: it is retaken, read back.
    if (std::isnan(readback_us)) return Outcome::kNoChunk;
  }
  const bool from_chunk = ChunkEvidence() && chunk_us.has_value();
  if (from_chunk) ++frames_with_chunk_;
  out->exposure_from_chunk = from_chunk;
  out->actual_exposure_us = from_chunk ? *chunk_us : readback_us;
  const double tolerance = options_.exposure_tolerance * plan.exposure_us;
  if (!(std::fabs(out->actual_exposure_us - plan.exposure_us) <= std::max(tolerance, 1e-6))) {
    out->status = FrameStatus::kWrongExposure;
    return Outcome::kWrongExposure;
  }
  out->status = FrameStatus::kOk;
  return Outcome::kOk;
}

std::chrono::steady_clock::time_point BracketCapture::StartFrame(const PlannedFrame& plan,
                                                                 const Trigger& trigger) {
  if (started_ahead_) {
    const auto started = *started_ahead_;
    started_ahead_.reset();
    return started;
  }
  trigger(plan.frame_in_bracket);
  return std::chrono::steady_clock::now();
}

bool BracketCapture::FiresAhead(const PlannedFrame& plan, const PlannedFrame& next) const {
  const double tolerance = options_.exposure_tolerance * std::max(plan.exposure_us, next.exposure_us);
  return options_.trigger_in_readout &&
         std::fabs(next.exposure_us - plan.exposure_us) > std::max(2.0 * tolerance, 1e-6);
}

BracketCapture::Outcome BracketCapture::Attempt(const PlannedFrame& plan, double readback_us,
                                                const Trigger& trigger, const PlannedFrame* next,
                                                BracketFrame* out) {
  const auto started = StartFrame(plan, trigger);
  const auto exposure_end = started + std::chrono::microseconds(std::llround(plan.exposure_us)) +
                            options_.pipeline_margin;
  std::optional<std::chrono::steady_clock::time_point> fired_next_at;
  if (next == nullptr && plan.frame_in_bracket == last_frame_ && during_last_readout_) {
    std::this_thread::sleep_until(exposure_end);
    during_last_readout_();
  }
  if (next != nullptr) {
    // The frame latched its exposure when it started: the next one can be written now, while
    // this frame is read out (and, with trigger_in_readout, the next frame triggered).
    std::this_thread::sleep_until(exposure_end);
    camera_.WriteExposureUs(next->exposure_us);
    if (FiresAhead(plan, *next)) {
      trigger(next->frame_in_bracket);
      fired_next_at = std::chrono::steady_clock::now();
      ++stats_.fired_in_readout;
    }
  }
  const Outcome outcome = AwaitFrame(plan, readback_us, started + options_.frame_timeout, out);
  if (fired_next_at) {
    if (outcome == Outcome::kOk) {
      started_ahead_ = std::max(*fired_next_at, std::chrono::steady_clock::now());
    } else {
      // The successor's frame is on its way: it must not be taken for this frame's retry.
      DiscardFrameFiredAhead(*next);
    }
  }
  return outcome;
}

void BracketCapture::DiscardFrameFiredAhead(const PlannedFrame& next) {
  const auto exposure = std::chrono::microseconds(std::llround(next.exposure_us));
  if (auto frame = camera_.WaitFrame(
          std::chrono::duration_cast<std::chrono::milliseconds>(exposure) + options_.frame_timeout)) {
    CountLeftover(*frame);
  }
}

void BracketCapture::CountFailure(Outcome outcome, BracketFrame* frame, AttemptLog* log) {
  switch (outcome) {
    case Outcome::kTimeout:
      ++stats_.timeouts;
      ++log->timeouts;
      frame->status = FrameStatus::kTimeout;
      break;
    case Outcome::kDamaged:
      ++stats_.damaged;
      ++log->damaged;
      break;
    case Outcome::kWrongExposure:
      ++stats_.wrong_exposure;
      ++log->wrong_exposure;
      log->last_exposure_us = frame->actual_exposure_us;
      log->last_from_chunk = frame->exposure_from_chunk;
      break;
    case Outcome::kNoChunk:
      ++log->no_chunk;
      break;
    case Outcome::kOk:
      break;
  }
}

bool BracketCapture::TakeFrame(const PlannedFrame& plan, const PlannedFrame* next,
                               const Trigger& trigger, BracketFrame* frame,
                               bool* next_programmed, AttemptLog* log) {
  frame->plan = plan;
  frame->requested_exposure_us = plan.exposure_us;
  bool pipelined = Pipelining();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  // On entry the camera holds this frame's exposure (written during the previous readout, or
  // programmed serially); a retry after a pipelined write programs it again.
  double readback_us = pipelined ? nan : ProgramExposure(plan.exposure_us);
  for (int attempt = 0;; ++attempt) {
    frame->retries = attempt;
    const Outcome outcome =
        Attempt(plan, readback_us, trigger, pipelined ? next : nullptr, frame);
    *next_programmed = pipelined && next != nullptr;
    if (outcome == Outcome::kOk) {
      // Taken unpipelined (a retry) while the bracket pipelines: the successor expects its
      // exposure in the camera on entry, so it is programmed now.
      if (!pipelined && next != nullptr && Pipelining()) ProgramExposure(next->exposure_us);
      return true;
    }
    if (outcome == Outcome::kNoChunk && !ChunkEvidence()) {
      // The chunks stopped: this frame is retaken with its exposure read back (no retry spent).
      pipelined = false;
      readback_us = ProgramExposure(plan.exposure_us);
      ++stats_.retried;
      --attempt;
      continue;
    }
    CountFailure(outcome, frame, log);
    if (attempt >= options_.max_retries) return false;
    ++stats_.retried;
    if (outcome == Outcome::kTimeout) DrainLateFrames();
    // A retry programs the exposure again, waits for the camera to report it, and takes the
    // frame without writing the successor's exposure during it: a trigger that reached the
    // sensor after that write (a loaded host, a slow trigger path) latched the successor's
    // exposure, and would again on every pipelined retry.
    pipelined = false;
    readback_us = ProgramExposure(plan.exposure_us);
  }
}

std::string BracketCapture::FailureText(const PlannedFrame& plan, const AttemptLog& log,
                                        const TransferStats& before) const {
  const TransferStats now = camera_.Transfer();
  const std::uint64_t missing = now.missing_packets - before.missing_packets;
  const std::uint64_t asked = now.resend_requests - before.resend_requests;
  const std::uint64_t resent = now.resent_packets - before.resent_packets;
  std::ostringstream why;
  why << "frame " << plan.frame_in_bracket << " (" << FrameRoleName(plan.role) << ", "
      << plan.exposure_us << " us) failed " << (options_.max_retries + 1) << " times ("
      << log.timeouts << " nothing in time, " << log.damaged << " incomplete, "
      << log.wrong_exposure << " wrong exposure, " << log.no_chunk << " without chunk)";
  if (log.damaged > 0 || missing > 0 || asked > 0) {
    why << ": packets were lost on the network (" << missing << " missing, " << asked
        << " asked again, " << resent << " resent): check the cable and the network card, the "
        << "MTU (jumbo frames) against the packet size (camera.packet_size), the socket buffer "
        << "and the camera's packet delay (GevSCPD); then the trigger wiring ("
        << options_.trigger_source << ")";
  } else if (log.timeouts > 0 && log.wrong_exposure == 0 && log.no_chunk == 0) {
    why << ": nothing arrived: check the trigger wiring (" << options_.trigger_source
        << "), the camera's trigger source and activation, that the trigger output fires, and "
        << "frame_timeout";
  } else if (log.no_chunk > 0) {
    why << ": the frames came without their ChunkExposureTime chunk although chunk mode is on "
        << "(camera.exposure_check: chunk): chunk data lost on the way (a NIC or switch), laid "
        << "out in a way Aravis cannot parse, or ignored by the firmware for this pixel format; "
        << "set camera.exposure_check: readback (or remove it: the chunk while frames carry it)";
  } else {
    why << ": the camera reported " << log.last_exposure_us << " us ("
        << (log.last_from_chunk ? "the frame's ChunkExposureTime chunk" : "read back")
        << ") for the " << plan.exposure_us << " us written: use exposures within its range "
        << "and increments (a camera that rounds them to its own steps needs exposures on them)";
  }
  return why.str();
}

void BracketCapture::PrepareStream(const Trigger& trigger) {
  if (!camera_.streaming()) {
    // A new stream: the camera may number its frames afresh (GigE Vision block ids restart with
    // acquisition on many cameras), and no frame of the old stream can arrive on it.
    have_last_ = false;
    camera_.StartStream();
    if (options_.warmup_trigger && options_.trigger_source != "Software") {
      ++stats_.warmup;
      trigger(-1);
      if (auto frame = camera_.WaitFrame(options_.frame_timeout)) {
        if (frame->status == FrameStatus::kOk) {
          AcceptId(frame->frame_id, frame->timestamp_ns);
        } else {
          CountFailedBuffer(frame->status);
        }
      }
    }
  }
  stats_.stray += camera_.Flush();
}

BracketResult BracketCapture::Capture(const Trigger& trigger, const FrameSink& on_frame,
                                      std::function<void()> during_last_readout) {
  IRDIST_CHECK(static_cast<bool>(trigger), "Capture() needs a trigger callable");
  during_last_readout_ = std::move(during_last_readout);
  ++stats_.brackets;
  PrepareStream(trigger);
  const std::vector<PlannedFrame> plan = PlanBracket(options_);
  started_ahead_.reset();
  last_frame_ = static_cast<int>(plan.size()) - 1;
  // Pipelined, the first exposure is programmed (and read back) while the camera is idle.
  if (Pipelining()) ProgramExposure(plan.front().exposure_us);
  const TransferStats transfer_before = camera_.Transfer();
  BracketResult result;
  for (size_t i = 0; i < plan.size(); ++i) {
    ++stats_.requested;
    const PlannedFrame* next = i + 1 < plan.size() ? &plan[i + 1] : nullptr;
    BracketFrame frame;
    bool next_programmed = false;
    AttemptLog log;
    if (!TakeFrame(plan[i], next, trigger, &frame, &next_programmed, &log)) {
      ++stats_.lost;
      ++stats_.brackets_failed;
      result.failure = FailureText(plan[i], log, transfer_before);
      result.complete = false;
      stats_.transfer = camera_.Transfer();
      return result;
    }
    if (next_programmed) ++stats_.pipelined_frames;
    ++stats_.received;
    result.frames.push_back(std::move(frame));
    if (on_frame) on_frame(result.frames.back());
  }
  result.complete = true;
  stats_.transfer = camera_.Transfer();
  return result;
}

}  // namespace irdist
