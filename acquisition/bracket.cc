#include "acquisition/bracket.h"

#include <cmath>
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
      << stray << ", id gaps " << id_gaps << ", warm-up " << warmup << "]";
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
    if (AcceptId(frame->frame_id, frame->timestamp_ns)) {
      ++stats_.late;
    } else {
      ++stats_.duplicates;
    }
  }
}

BracketCapture::Outcome BracketCapture::Attempt(const PlannedFrame& plan, double readback_us,
                                                const Trigger& trigger, BracketFrame* out) {
  trigger(plan.frame_in_bracket);
  const auto deadline = std::chrono::steady_clock::now() + options_.frame_timeout;
  while (true) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) return Outcome::kTimeout;
    std::optional<RawFrame> frame = camera_.WaitFrame(left);
    if (!frame) return Outcome::kTimeout;
    if (!AcceptId(frame->frame_id, frame->timestamp_ns)) {
      ++stats_.duplicates;
      continue;
    }
    out->frame_id = frame->frame_id;
    out->timestamp_ns = frame->timestamp_ns;
    out->host_time_ns = frame->host_time_ns;
    out->status = frame->status;
    if (frame->status != FrameStatus::kOk) {
      return frame->status == FrameStatus::kTimeout ? Outcome::kTimeout : Outcome::kDamaged;
    }
    out->image = std::move(frame->image);
    out->bit_depth = frame->bit_depth;
    out->exposure_from_chunk = frame->chunk_exposure_us.has_value();
    out->actual_exposure_us = frame->chunk_exposure_us.value_or(readback_us);
    const double tolerance = options_.exposure_tolerance * plan.exposure_us;
    if (std::fabs(out->actual_exposure_us - plan.exposure_us) > std::max(tolerance, 1e-6)) {
      out->status = FrameStatus::kWrongExposure;
      return Outcome::kWrongExposure;
    }
    return Outcome::kOk;
  }
}

BracketResult BracketCapture::Capture(const Trigger& trigger) {
  IRDIST_CHECK(static_cast<bool>(trigger), "Capture() needs a trigger callable");
  ++stats_.brackets;
  if (!camera_.streaming()) {
    camera_.StartStream();
    if (options_.warmup_trigger && options_.trigger_source != "Software") {
      ++stats_.warmup;
      trigger(-1);
      if (auto frame = camera_.WaitFrame(options_.frame_timeout)) {
        AcceptId(frame->frame_id, frame->timestamp_ns);
      }
    }
  }
  stats_.stray += camera_.Flush();

  BracketResult result;
  for (const PlannedFrame& plan : PlanBracket(options_)) {
    ++stats_.requested;
    // The previous frame has arrived (or been given up), so this write cannot reach it.
    const double readback_us = camera_.SetExposureUs(plan.exposure_us);
    BracketFrame frame;
    frame.plan = plan;
    frame.requested_exposure_us = plan.exposure_us;
    Outcome outcome = Outcome::kTimeout;
    for (int attempt = 0;; ++attempt) {
      frame.retries = attempt;
      outcome = Attempt(plan, readback_us, trigger, &frame);
      if (outcome == Outcome::kOk) break;
      switch (outcome) {
        case Outcome::kTimeout:
          ++stats_.timeouts;
          frame.status = FrameStatus::kTimeout;
          break;
        case Outcome::kDamaged:
          ++stats_.damaged;
          break;
        case Outcome::kWrongExposure:
          ++stats_.wrong_exposure;
          break;
        case Outcome::kOk:
          break;
      }
      if (attempt >= options_.max_retries) break;
      ++stats_.retried;
      if (outcome == Outcome::kTimeout) DrainLateFrames();
    }
    if (outcome != Outcome::kOk) {
      ++stats_.lost;
      ++stats_.brackets_failed;
      std::ostringstream why;
      why << "frame " << plan.frame_in_bracket << " (" << FrameRoleName(plan.role) << ", "
          << plan.exposure_us << " us) failed " << (options_.max_retries + 1)
          << " times, last outcome " << FrameStatusName(frame.status)
          << "; check the trigger wiring (" << options_.trigger_source
          << "), the network and frame_timeout";
      result.failure = why.str();
      result.complete = false;
      return result;
    }
    ++stats_.received;
    result.frames.push_back(std::move(frame));
  }
  result.complete = true;
  return result;
}

}  // namespace irdist
