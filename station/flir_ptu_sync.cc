// The FLIR PTU driver's line kept in step, and the unit's resets (docs/devices/flir_ptu.md):
// the lines that come unasked, the resynchronisation on V (waiting out a reset, whatever the unit
// prints meanwhile), the power-up banner as a restart, the unit's own confirmation that its
// moves ended (A) and the checks that find a restart. The class: station/flir_ptu_driver.h.

#include <thread>

#include "station/flir_ptu_driver.h"

namespace irdist::flir_ptu_internal {

// Manual: "!P" / "!T": the axis hit a limit and lost synchrony.
void FlirPtu::LimitHit(const std::string& line) const {
  const bool pan = line.find('P', line.find('!')) != std::string::npos;
  Fail(line, std::string(pan ? "pan" : "tilt") + " axis hit its limit (the unit's own report)",
       "the unit lost synchrony: check for an obstruction, then home (reset) it and resume");
}

// The lines that arrived unasked since the last reply (late replies, the unit's reports): a
// limit hit among them is reported (once homed), the rest dropped.
void FlirPtu::TakePending(bool report_limit_hit) {
  for (const std::string& line : link_->ReadPending()) {
    NotePowerUpText(line);
    if (report_limit_hit && homed_ && IsLimitHit(line)) {
      homed_ = false;
      LimitHit(line);
    }
  }
}

bool FlirPtu::IsVersion(const std::string& line) const {
  const std::size_t mark = line.find('*');
  if (mark == std::string::npos) return false;
  if (!version_.empty()) return line.find(version_, mark) != std::string::npos;
  return ptu_text::NamesAPanTiltUnit(line.substr(mark));
}

// Sends V and reads until its answer, then on until the line is quiet: every other line answers
// an earlier command (stale replies of a reset, of a previous session, whose own V may answer
// first). A resetting unit answers nothing, or prints its banner, "Initializing..." and the echo
// of commands: either is waited for, up to reset_wait_s. A device that answers other text, never
// as a PTU, is refused after `attempts` V's. A power-up seen on the way (the unit lost its
// reference) is a DeviceRestarted once the line is in step again.
void FlirPtu::SyncOnVersion() {
  TakePending(true);
  VersionSync sync;
  sync.deadline = Clock::now() + reset_wait_;
  link_->WriteLine("V");
  while (!SyncStep(&sync)) {
  }
  out_of_step_ = false;
  NotePowerUp();
}

// One line (or one silence) of SyncOnVersion; true when the line is in step.
bool FlirPtu::SyncStep(VersionSync* sync) {
  if (Clock::now() >= sync->deadline) {
    if (sync->answered > 0) return true;
    LinkFail("no answer to V within reset_wait_s (" + std::to_string(reset_wait_.count()) +
                 " ms)" + (sync->heard.empty() ? "" : "; last heard '" + sync->heard + "'"),
             "check the unit's power, cable and baud rate (PTU default 9600)");
  }
  std::string line;
  try {
    // Replies come in order: after a version only the answers to the other V's can follow,
    // back to back (a 50-character line takes 52 ms at 9600 baud).
    line = link_->ReadLine(sync->answered > 0 ? std::min(timeout_, kQuietAfterVersion) : timeout_);
  } catch (const LinkError&) {
    if (sync->answered > 0) return true;  // quiet after the version: nothing stale is left
    if (!sync->resetting && !sync->heard.empty() && ++sync->unanswered >= attempts_) {
      const std::size_t mark = sync->heard.find('*');
      if (!version_.empty() && mark != std::string::npos &&
          ptu_text::NamesAPanTiltUnit(sync->heard.substr(mark))) {  // a PTU, another version
        Fail(sync->heard, "a pan-tilt unit answers V, but not with the version identified at "
                          "connection ('" + version_ + "')",
             "check that the PTU on this port is the one the run started with; then start again");
      }
      Fail(sync->heard, "the device on this port answers, but never with a pan-tilt unit's version",
           "connect the PTU to this port or fix the rig file's port");
    }
    link_->WriteLine("V");
    return false;
  }
  if (IsLimitHit(line) && homed_) {
    homed_ = false;
    LimitHit(line);
  }
  NotePowerUpText(line);
  if (IsVersion(line)) {
    ++sync->answered;
  } else if (sync->answered == 0) {
    sync->heard = line;
    // The unit's banner, "Initializing..." or an echo: a PTU busy resetting, waited for.
    sync->resetting = sync->resetting || ptu_text::IsResetChatter(line);
  }
  return false;
}

void FlirPtu::NotePowerUpText(const std::string& line) const {
  if (ptu_text::IsPowerUpText(line)) power_up_seen_ = true;
}

// The unit printed its power-up banner since the last check: if it was homed, it lost its
// reference (the power-up reset moves the axes and restores the default settings).
void FlirPtu::NotePowerUp() {
  if (!power_up_seen_) return;
  power_up_seen_ = false;
  if (!homed_) return;
  homed_ = false;
  moving_ = false;
  restarted_ = true;
  throw DeviceRestarted(identity_.Brief() + ": the unit printed its power-up banner "
                            "(Initializing...): it was power-cycled or reset; home it and retake",
                        false);
}

// Every axis stands still and one is away from its target. Back at 0/0 (where the power-up reset
// leaves the unit) after being elsewhere, or with the rig's speed gone back to the default: the
// unit restarted. An axis stuck at 0 since the move began is not told apart from it.
void FlirPtu::StoppedShort(const std::string& what, const std::vector<long long>& positions) {
  Stop();
  bool at_power_up_pose = was_away_, speed_reset = false;
  std::string short_axes;
  for (std::size_t i = 0; i < axes_.size(); ++i) {
    at_power_up_pose = at_power_up_pose && positions[i] == 0;
    if (std::llabs(positions[i] - axes_[i].target) > tolerance_) {
      short_axes += (short_axes.empty() ? "" : ", ") + AxisText(axes_[i]) + " at " +
                    std::to_string(positions[i]) + " (target " +
                    std::to_string(axes_[i].target) + ")";
    }
    if (spec_.settings.count("speed_deg_s")) {
      const std::string p(1, axes_[i].letter);
      speed_reset = speed_reset || std::llround(QueryNumber(p + "S")) != axes_[i].speed_pos_s;
    }
  }
  if (homed_ && (at_power_up_pose || speed_reset)) {
    homed_ = false;
    moving_ = false;
    restarted_ = true;
    throw DeviceRestarted(identity_.Brief() + ": " + what + " ended with " + short_axes +
                              (speed_reset ? ", speeds reset" : ", at the power-up pose 0/0") +
                              ": the unit was power-cycled or reset; home it and retake",
                          false);
  }
  Fail("", what + " stopped short: " + short_axes,
       "check for an obstruction, an overload or a stalled axis; then home");
}

// No frame before the unit itself says its moves ended: positions read at the target may still
// be a move's last fraction of a step, or answers to earlier queries. A (await) is answered only
// once both axes have stopped, after every command sent before it; while no reply was missed the
// line is in step (replies come in order), so the next '*' is A's. A lost or late reply is never
// taken for it: the miss puts the line out of step, which the next attempt brings back in step
// (V) before asking A again (it moves nothing).
void FlirPtu::ConfirmStopped(milliseconds timeout) {
  const milliseconds wait = std::min(timeout, std::max(timeout_, milliseconds(2000)));
  for (int attempt = 0; attempt < attempts_; ++attempt) {
    std::string body;
    LineRequest request = Request("A", &body);
    request.judge = [this, &body](const std::string& line) {
      if (IsVersion(line)) return ReplyVerdict::kSkip;  // a V of the resynchronisation, late
      return Judge("A", line, &body);
    };
    if (query_.AskOnce(request, wait).has_value()) return;
  }
  LinkFail("the unit never confirmed the end of its moves (A, await: " +
               std::to_string(attempts_) + " attempts of " + std::to_string(wait.count()) + " ms)",
           "check the cable and the unit's power; nothing is exposed before the confirmation");
}

// After a reset the unit is back to its power-up settings (echo on, verbose feedback): it is
// identified again (echo off, terse, immediate mode), and must be the same unit.
void FlirPtu::Reidentify() {
  const std::string before = version_;
  SyncOnVersion();
  Query("ED");
  Query("FT");
  const std::string version = Query("V");
  if (!before.empty() && version != before) {
    Fail(version, "after its reset the unit answers V with '" + version + "', not '" + before +
                      "' as at connection",
         "check that the PTU on this port is the one the run started with; then start again");
  }
  Query("I");
  restarted_ = false;
}

// At rest, an axis away from its target or speeds back to their defaults: the unit restarted
// (its power-up reset moves the axes and resets the settings).
void FlirPtu::CheckAlive() {
  for (const PtuAxis& a : axes_) {
    const long long pos = (!homed_ || moving_ || !a.has_target) ? Position(a) : StablePosition(a);
    if (!homed_ || moving_ || !a.has_target) continue;
    const bool moved = std::llabs(pos - a.target) > tolerance_;
    const bool reset = spec_.settings.count("speed_deg_s") &&
                       std::llround(QueryNumber(std::string(1, a.letter) + "S")) != a.speed_pos_s;
    if (moved || reset) {
      homed_ = false;
      restarted_ = true;
      throw DeviceRestarted(identity_.Brief() + ": " + AxisText(a) + " at " +
                                std::to_string(pos) + " instead of " + std::to_string(a.target) +
                                (reset ? " and its speed reset" : "") +
                                ": the unit was power-cycled or reset; home it and retake",
                            false);
    }
  }
}

}  // namespace irdist::flir_ptu_internal
