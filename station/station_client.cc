#include "station/station_client.h"

#include <cmath>
#include <cstdio>
#include <sstream>
#include <thread>

namespace irdist {

namespace {

std::vector<std::string> Split(const std::string& text, char sep) {
  std::vector<std::string> out;
  std::string cur;
  for (char c : text) {
    if (c == sep) {
      out.push_back(cur);
      cur.clear();
    } else {
      cur.push_back(c);
    }
  }
  out.push_back(cur);
  return out;
}

long long ParseCount(const std::string& text, std::string_view command) {
  std::size_t used = 0;
  long long value = 0;
  try {
    value = std::stoll(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size()) {
    throw StationError(0, "station sent a malformed number '" + text + "' in reply to " +
                              std::string(command) +
                              "; check that the firmware implements docs/station-protocol.md");
  }
  return value;
}

std::vector<long long> ParseCounts(const std::string& payload, std::size_t n,
                                   std::string_view command) {
  const std::vector<std::string> parts = Split(payload, ',');
  if (parts.size() != n) {
    throw StationError(0, "station sent '" + payload + "' to " + std::string(command) +
                              ", expected " + std::to_string(n) +
                              " numbers; check the firmware against docs/station-protocol.md");
  }
  std::vector<long long> out;
  for (const std::string& p : parts) out.push_back(ParseCount(p, command));
  return out;
}

StationState ParseState(const std::string& name) {
  if (name == "UNHOMED") return StationState::kUnhomed;
  if (name == "HOMING") return StationState::kHoming;
  if (name == "IDLE") return StationState::kIdle;
  if (name == "MOVING") return StationState::kMoving;
  if (name == "SETTLING") return StationState::kSettling;
  if (name == "ESTOP") return StationState::kEStop;
  return StationState::kUnknown;
}

long long ToCenti(double value) { return std::llround(value * 100.0); }

}  // namespace

std::string StationStateName(StationState state) {
  switch (state) {
    case StationState::kUnhomed: return "UNHOMED";
    case StationState::kHoming: return "HOMING";
    case StationState::kIdle: return "IDLE";
    case StationState::kMoving: return "MOVING";
    case StationState::kSettling: return "SETTLING";
    case StationState::kEStop: return "ESTOP";
    case StationState::kUnknown: return "UNKNOWN";
  }
  return "UNKNOWN";
}

bool ClientOptions::IsValid(std::string* why) const {
  auto fail = [&](const char* m) {
    if (why) *why = m;
    return false;
  };
  if (reply_timeout.count() <= 0) return fail("reply_timeout must be > 0");
  if (max_retries < 0) return fail("max_retries must be >= 0");
  if (poll_period.count() < 0) return fail("poll_period must be >= 0");
  if (move_timeout.count() <= 0) return fail("move_timeout must be > 0");
  if (!(slide_tolerance_mm >= 0.005)) return fail("slide_tolerance_mm must be >= 0.005");
  if (!(angle_tolerance_deg >= 0.005)) return fail("angle_tolerance_deg must be >= 0.005");
  if (settled_polls < 1) return fail("settled_polls must be >= 1");
  if (max_move_attempts < 1) return fail("max_move_attempts must be >= 1");
  return true;
}

std::string ClientStats::BriefReport() const {
  std::ostringstream out;
  out << "station link: " << requests << " requests, " << resends << " resends, " << timeouts
      << " timeouts, " << damaged << " damaged replies, " << stale << " stale replies, "
      << reboots << " reboots";
  return out.str();
}

StationClient::StationClient(Transport& transport, ClientOptions options)
    : transport_(transport), options_(options) {
  std::string why;
  IRDIST_CHECK(options_.IsValid(&why), why);
}

Reply StationClient::Exchange(std::string_view command) {
  const int seq = next_seq_;
  next_seq_ = next_seq_ >= kMaxSequence ? 0 : next_seq_ + 1;
  const std::string line = EncodeRequest(seq, command);
  ++stats_.requests;
  for (int attempt = 0; attempt <= options_.max_retries; ++attempt) {
    if (attempt > 0) ++stats_.resends;
    transport_.WriteLine(line);
    const auto deadline = std::chrono::steady_clock::now() + options_.reply_timeout;
    while (true) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          deadline - std::chrono::steady_clock::now());
      if (left.count() <= 0) {
        ++stats_.timeouts;
        break;
      }
      std::string raw;
      try {
        raw = transport_.ReadLine(left);
      } catch (const LinkError&) {
        ++stats_.timeouts;
        break;  // resend: the station answers a retransmission from its reply cache
      }
      std::string why;
      const std::optional<Reply> reply = DecodeReply(raw, &why);
      if (!reply) {
        ++stats_.damaged;
        break;  // possibly ours: ask again at once
      }
      if (reply->seq != seq) {
        ++stats_.stale;  // a late copy of an earlier reply
        continue;
      }
      return *reply;
    }
  }
  throw LinkError("no valid reply to '" + std::string(command) + "' after " +
                      std::to_string(options_.max_retries + 1) + " attempts of " +
                      std::to_string(options_.reply_timeout.count()) + " ms",
                  "station link", "check the cable, the port and the baud rate in the rig file");
}

std::string StationClient::Command(std::string_view command) {
  const Reply reply = Exchange(command);
  if (reply.ok) return reply.payload;
  if (reply.error_code == 201 && homed_ && !recovering_) {
    Status();  // "not homed" although we homed it: a reboot? (throws StationRebooted if so)
  }
  std::string fix = "see docs/station-protocol.md, errors";
  if (reply.error_code == -222) fix = "keep the target within the station's soft limits (LIM?)";
  if (reply.error_code == 201) fix = "home the station first";
  if (reply.error_code == 202) fix = "clear the emergency stop (ESTOP:CLR) and home again";
  if (reply.error_code == -221) fix = "wait until the station is idle (or STOP it) first";
  throw StationError(reply.error_code, "station refused '" + std::string(command) + "': " +
                                           std::to_string(reply.error_code) + " " +
                                           reply.error_text + "; " + fix);
}

StationIdentity StationClient::Identify() {
  const std::string payload = Command("*IDN?");
  const std::vector<std::string> parts = Split(payload, ',');
  if (parts.size() != 5 || parts[4].empty()) {
    throw StationError(0, "station identified itself as '" + payload +
                              "', expected vendor,model,serial,firmware,boot_id; check the "
                              "firmware against docs/station-protocol.md");
  }
  StationIdentity id{parts[0], parts[1], parts[2], parts[3], parts[4]};
  if (boot_id_.empty()) {
    boot_id_ = id.boot_id;
  } else if (id.boot_id != boot_id_) {
    OnBootId(id.boot_id);
  }
  return id;
}

StationStatus StationClient::StatusNoCheck() {
  const std::string payload = Command("STAT?");
  const std::vector<std::string> parts = Split(payload, ',');
  if (parts.size() != 2) {
    throw StationError(0, "station sent '" + payload + "' to STAT?, expected state,boot_id");
  }
  return {ParseState(parts[0]), parts[1]};
}

StationStatus StationClient::Status() {
  const StationStatus status = StatusNoCheck();
  if (!boot_id_.empty() && status.boot_id != boot_id_) OnBootId(status.boot_id);
  return status;
}

void StationClient::OnBootId(const std::string& seen) {
  // Confirm with *IDN? (a reply damaged in a way the checksum missed must not trigger recovery).
  const std::vector<std::string> parts = Split(Command("*IDN?"), ',');
  const std::string now = parts.size() == 5 ? parts[4] : seen;
  if (now == boot_id_) return;
  const std::string old = boot_id_;
  boot_id_ = now;
  homed_ = false;
  ++stats_.reboots;
  if (!options_.recover_on_reboot || recovering_) throw StationRebooted(old, now, false);
  recovering_ = true;
  try {
    DrainErrors();
    Home();
    const double restore = current_ma_;
    current_ma_ = -1.0;
    SetCurrent(restore);
  } catch (...) {
    recovering_ = false;
    throw;
  }
  recovering_ = false;
  throw StationRebooted(old, now, true);
}

// An IDLE off the target on this many consecutive polls is a failed move (the protocol's section 4).
constexpr int kOffTargetPolls = 2;

void StationClient::WaitMotionDone(const char* what, const long long* target_centi) {
  const auto give_up = std::chrono::steady_clock::now() + options_.move_timeout;
  int good = 0;
  int idle_off_target = 0;
  while (true) {
    const StationStatus status = Status();
    bool in_tolerance = true;
    if (target_centi != nullptr && status.state == StationState::kIdle) {
      const StationPosition p = Position();
      in_tolerance = std::fabs(p.slide_mm - target_centi[0] / 100.0) <=
                         options_.slide_tolerance_mm + 1e-9 &&
                     std::fabs(p.pan_deg - target_centi[1] / 100.0) <=
                         options_.angle_tolerance_deg + 1e-9 &&
                     std::fabs(p.tilt_deg - target_centi[2] / 100.0) <=
                         options_.angle_tolerance_deg + 1e-9;
    }
    switch (status.state) {
      case StationState::kIdle:
        if (in_tolerance) {
          idle_off_target = 0;
          if (++good >= options_.settled_polls) return;
        } else {
          good = 0;
          if (++idle_off_target >= kOffTargetPolls) {
            throw StationError(0, std::string(what) + " ended off target");
          }
        }
        break;
      case StationState::kUnhomed:
        if (homed_ || target_centi == nullptr) {
          homed_ = false;
          const std::vector<StationErrorEntry> errors = DrainErrors();
          std::string detail;
          for (const StationErrorEntry& e : errors) {
            detail += " [" + std::to_string(e.code) + " " + e.message + "]";
          }
          throw StationError(204, std::string(what) + " failed: station is UNHOMED" + detail +
                                      "; check the axes for an obstruction and home again");
        }
        break;
      case StationState::kEStop:
        throw StationError(202, std::string(what) + " interrupted by an emergency stop; clear "
                                                    "it (ESTOP:CLR) and home again");
      default:
        good = 0;
        break;
    }
    if (std::chrono::steady_clock::now() > give_up) {
      throw StationError(0, std::string(what) + " not settled within " +
                                std::to_string(options_.move_timeout.count()) +
                                " ms; check the axes and ClientOptions::move_timeout");
    }
    std::this_thread::sleep_for(options_.poll_period);
  }
}

void StationClient::Home() {
  if (boot_id_.empty()) Identify();
  homed_ = false;
  Command("HOME");
  WaitMotionDone("homing", nullptr);
  homed_ = true;
}

void StationClient::MoveTo(const StationPosition& target) {
  StartMove(target);
  WaitMoveSettled();
}

void StationClient::StartMove(const StationPosition& target) {
  IRDIST_CHECK(std::isfinite(target.slide_mm) && std::isfinite(target.pan_deg) &&
                   std::isfinite(target.tilt_deg),
               "non-finite move target");
  move_target_ = target;
  move_centi_[0] = ToCenti(target.slide_mm);
  move_centi_[1] = ToCenti(target.pan_deg);
  move_centi_[2] = ToCenti(target.tilt_deg);
  Command(MoveCommand());
}

std::string StationClient::MoveCommand() const {
  char command[96];
  std::snprintf(command, sizeof(command), "MOVE %lld,%lld,%lld", move_centi_[0], move_centi_[1],
                move_centi_[2]);
  return command;
}

void StationClient::WaitMoveSettled() {
  for (int attempt = 1;; ++attempt) {
    try {
      WaitMotionDone("move", move_centi_);
      return;
    } catch (const StationError& e) {
      if (e.code() != 0) throw;
      if (attempt >= options_.max_move_attempts) ThrowStuck(attempt);
    }
    Command(MoveCommand());  // ended off target: reissue
  }
}

void StationClient::ThrowStuck(int attempts) {
  const StationPosition p = Position();
  const StationPosition& target = move_target_;
  char detail[200];
  std::snprintf(detail, sizeof(detail),
                "move to %.2f mm, %.2f deg, %.2f deg ended at %.2f mm, %.2f deg, %.2f deg "
                "after %d attempts",
                target.slide_mm, target.pan_deg, target.tilt_deg, p.slide_mm, p.pan_deg,
                p.tilt_deg, attempts);
  throw StationError(0, std::string(detail) + "; an axis is stuck or blocked: check the mechanics");
}

StationPosition StationClient::Position() {
  const std::vector<long long> v = ParseCounts(Command("POS?"), 3, "POS?");
  return {v[0] / 100.0, v[1] / 100.0, v[2] / 100.0};
}

SoftLimits StationClient::GetSoftLimits() {
  const std::vector<long long> v = ParseCounts(Command("LIM?"), 6, "LIM?");
  return {v[0] / 100.0, v[1] / 100.0, v[2] / 100.0, v[3] / 100.0, v[4] / 100.0, v[5] / 100.0};
}

void StationClient::SetSoftLimit(const std::string& axis, double min, double max) {
  IRDIST_CHECK(axis == "SLIDE" || axis == "PAN" || axis == "TILT", "axis ", axis);
  Command("LIM " + axis + "," + std::to_string(ToCenti(min)) + "," +
          std::to_string(ToCenti(max)));
}

void StationClient::SetSpeed(const std::string& axis, double unit_per_s) {
  IRDIST_CHECK(axis == "SLIDE" || axis == "PAN" || axis == "TILT", "axis ", axis);
  IRDIST_CHECK(std::isfinite(unit_per_s) && unit_per_s > 0.0, "speed ", unit_per_s);
  Command("SPEED " + axis + "," + std::to_string(ToCenti(unit_per_s)));
}

void StationClient::SetCurrent(double bias_ma) {
  IRDIST_CHECK(std::isfinite(bias_ma) && bias_ma >= 0.0, "bias_ma ", bias_ma);
  Command("SOUR:CURR " + std::to_string(ToCenti(bias_ma)));
  current_ma_ = ToCenti(bias_ma) / 100.0;
}

double StationClient::MeasureCurrent() {
  return ParseCounts(Command("MEAS:CURR?"), 1, "MEAS:CURR?")[0] / 100.0;
}

void StationClient::Trigger(int count, double width_us, double period_us) {
  IRDIST_CHECK(count >= 1 && width_us > 0 && period_us > width_us, "count ", count, " width ",
               width_us, " period ", period_us);
  const long long width_rounded = std::llround(width_us);
  const long long period_rounded = std::llround(period_us);
  // Settings survive until the next power-up; a reboot changes the boot id (seen by Pulses()'s
  // caller through Status(), or here through the cache key) and they are sent again.
  const bool programmed = trigger_boot_id_ == boot_id_ && !boot_id_.empty() &&
                          trigger_count_ == count && trigger_width_us_ == width_rounded &&
                          trigger_period_us_ == period_rounded;
  if (!programmed) {
    trigger_boot_id_.clear();
    const std::string width = "TRIG:WIDT " + std::to_string(width_rounded);
    const std::string period = "TRIG:PER " + std::to_string(period_rounded);
    Command("TRIG:COUN " + std::to_string(count));
    // The station keeps width < period at all times: order the two settings accordingly.
    const Reply first = Exchange(width);
    if (!first.ok) {
      Command(period);
      Command(width);
    } else {
      Command(period);
    }
    trigger_boot_id_ = boot_id_;
    trigger_count_ = count;
    trigger_width_us_ = width_rounded;
    trigger_period_us_ = period_rounded;
  }
  Command("TRIG:FIRE");
}

PulseCounter StationClient::Pulses() {
  const std::vector<long long> v = ParseCounts(Command("TRIG:PULS?"), 2, "TRIG:PULS?");
  return {static_cast<std::uint64_t>(v[0]), static_cast<std::uint64_t>(v[1])};
}

std::uint64_t StationClient::WaitTriggerDone() {
  const auto give_up = std::chrono::steady_clock::now() + options_.move_timeout;
  while (true) {
    const PulseCounter c = Pulses();
    if (c.remaining == 0) return c.total;
    if (std::chrono::steady_clock::now() > give_up) {
      throw StationError(0, "trigger train not done within " +
                                std::to_string(options_.move_timeout.count()) + " ms");
    }
    std::this_thread::sleep_for(options_.poll_period);
  }
}

void StationClient::Stop() {
  Command("STOP");
  const auto give_up = std::chrono::steady_clock::now() + options_.move_timeout;
  while (true) {
    const StationState s = Status().state;
    if (s != StationState::kMoving && s != StationState::kSettling && s != StationState::kHoming) {
      if (s == StationState::kUnhomed) homed_ = false;
      return;
    }
    if (std::chrono::steady_clock::now() > give_up) {
      throw StationError(0, "station did not stop within the move timeout; use EStop");
    }
    std::this_thread::sleep_for(options_.poll_period);
  }
}

void StationClient::EStop() {
  Command("ESTOP");
  homed_ = false;
  current_ma_ = 0.0;
}

void StationClient::ClearEStop() { Command("ESTOP:CLR"); }

std::vector<StationErrorEntry> StationClient::DrainErrors() {
  std::vector<StationErrorEntry> out;
  for (int i = 0; i < 64; ++i) {
    const std::string payload = Command("SYST:ERR?");
    const std::size_t comma = payload.find(',');
    const long long code = ParseCount(payload.substr(0, comma), "SYST:ERR?");
    if (code == 0) return out;
    std::string message = comma == std::string::npos ? "" : payload.substr(comma + 1);
    if (message.size() >= 2 && message.front() == '"' && message.back() == '"') {
      message = message.substr(1, message.size() - 2);
    }
    out.push_back({static_cast<int>(code), message});
  }
  return out;
}

}  // namespace irdist
