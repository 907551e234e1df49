#include "station/conformance.h"

#include <cmath>
#include <cstdio>
#include <functional>
#include <optional>
#include <sstream>
#include <thread>

#include "base/check.h"
#include "station/frame.h"
#include "station/station_client.h"

namespace irdist {
namespace {

// A check's failure: what was expected and what came.
class Nonconformance : public Error {
 public:
  using Error::Error;
};

void Expect(bool ok, const std::string& what) {
  if (!ok) throw Nonconformance(what);
}

// The reply's error code (0 for OK).
int CodeOf(StationClient& client, const std::string& command) {
  const Reply reply = client.Exchange(command);
  return reply.ok ? 0 : reply.error_code;
}

void ExpectCode(StationClient& client, const std::string& command, int code) {
  const int got = CodeOf(client, command);
  Expect(got == code, "'" + command + "' answered " + (got == 0 ? "OK" : std::to_string(got)) +
                          ", expected " + (code == 0 ? "OK" : std::to_string(code)));
}

std::string StateOf(StationClient& client) {
  return StationStateName(client.Status().state);
}

void WaitIdle(StationClient& client, const ConformanceOptions& o) {
  const auto give_up = std::chrono::steady_clock::now() + o.move_timeout;
  while (std::chrono::steady_clock::now() < give_up) {
    if (client.Status().state == StationState::kIdle) return;
    std::this_thread::sleep_for(o.poll_period);
  }
  throw Nonconformance("not IDLE within " + std::to_string(o.move_timeout.count()) + " ms");
}

// The suite's own frames on the raw link (sequence numbers far from the client's).
class RawLink {
 public:
  RawLink(Transport& t, const ConformanceOptions& o) : t_(t), o_(o) {}
  std::optional<Reply> Send(const std::string& line) {
    t_.WriteLine(line);
    try {
      std::string why;
      return DecodeReply(t_.ReadLine(o_.reply_timeout), &why);
    } catch (const LinkError&) {
      return std::nullopt;
    }
  }

 private:
  Transport& t_;
  const ConformanceOptions& o_;
};

struct Suite {
  Transport& transport;
  StationClient& client;
  const ConformanceOptions& options;
  ConformanceReport report;
  void Run(const char* name, const char* section, const std::function<void()>& check) {
    ConformanceCheck c{name, section, true, ""};
    try {
      check();
    } catch (const Error& e) {
      c.passed = false;
      c.detail = e.what();
    }
    report.checks.push_back(c);
  }
};

void IdentityChecks(Suite& s) {
  s.Run("identity", "5 *IDN?", [&] {
    const StationIdentity id = s.client.Identify();
    Expect(id.boot_id.size() == 8 && id.boot_id.find_first_not_of("0123456789ABCDEFabcdef") ==
                                         std::string::npos,
           "boot id '" + id.boot_id + "' is not 8 hex digits");
  });
  s.Run("unknown-command", "6 -113", [&] { ExpectCode(s.client, "NOSUCH:CMD", -113); });
  s.Run("checksum", "2 CRC-8, no reply to a damaged line", [&] {
    s.client.DrainErrors();
    std::string line = EncodeRequest(9990, "STAT?");
    line.back() = line.back() == '0' ? '1' : '0';  // damage the checksum
    RawLink raw(s.transport, s.options);
    Expect(!raw.Send(line).has_value(), "a line with a wrong checksum got a reply");
    bool queued = false;
    for (const StationErrorEntry& e : s.client.DrainErrors()) queued = queued || e.code == 203;
    Expect(queued, "error 203 not queued");
  });
  s.Run("error-queue-overflow", "6 depth 16, -350", [&] {
    s.client.DrainErrors();
    for (int i = 0; i < 20; ++i) s.client.Exchange("NOSUCH:CMD");
    const std::vector<StationErrorEntry> errors = s.client.DrainErrors();
    Expect(errors.size() == 16, "queue held " + std::to_string(errors.size()) + " entries");
    Expect(errors.back().code == -350, "last entry " + std::to_string(errors.back().code) +
                                           ", expected -350");
  });
}

void EStopChecks(Suite& s) {
  s.Run("estop", "4 ESTOP", [&] {
    ExpectCode(s.client, "ESTOP", 0);
    Expect(StateOf(s.client) == "ESTOP", "state " + StateOf(s.client));
  });
  s.Run("estop-current-off", "5 SOUR:CURR 0 always accepted",
        [&] { ExpectCode(s.client, "SOUR:CURR 0", 0); });
  s.Run("estop-refuses", "5 ESTOP: MOVE, current, FIRE refused (202)", [&] {
    ExpectCode(s.client, "SOUR:CURR 10000", 202);
    ExpectCode(s.client, "TRIG:FIRE", 202);
    ExpectCode(s.client, "MOVE 0,0,0", 202);
  });
  s.Run("estop-clear", "4 ESTOP:CLR -> UNHOMED", [&] {
    ExpectCode(s.client, "ESTOP:CLR", 0);
    Expect(StateOf(s.client) == "UNHOMED", "state " + StateOf(s.client));
    ExpectCode(s.client, "MOVE 0,0,0", 201);
  });
}

void MotionChecks(Suite& s) {
  s.Run("home-while-homing", "5 HOME while HOMING accepted", [&] {
    ExpectCode(s.client, "HOME", 0);
    ExpectCode(s.client, "HOME", 0);
    WaitIdle(s.client, s.options);
  });
  s.Run("soft-limits", "5 MOVE outside LIM? -> -222", [&] {
    const SoftLimits lim = s.client.GetSoftLimits();
    char move[96];
    std::snprintf(move, sizeof(move), "MOVE %lld,0,0", std::llround(lim.slide_max_mm * 100) + 1);
    ExpectCode(s.client, move, -222);
  });
  s.Run("move-settled", "7 IDLE within 0.01 of the target", [&] {
    const SoftLimits lim = s.client.GetSoftLimits();
    const StationPosition target{0.5 * (lim.slide_min_mm + lim.slide_max_mm), 1.0, -1.0};
    s.client.MoveTo(target);
    const StationPosition p = s.client.Position();
    Expect(std::fabs(p.slide_mm - target.slide_mm) <= 0.0100001 &&
               std::fabs(p.pan_deg - target.pan_deg) <= 0.0100001 &&
               std::fabs(p.tilt_deg - target.tilt_deg) <= 0.0100001,
           "settled off target");
  });
  s.Run("stop-end-state", "5 STOP ends IDLE, homed", [&] {
    const SoftLimits lim = s.client.GetSoftLimits();
    s.client.StartMove({lim.slide_min_mm, 0.0, 0.0});
    ExpectCode(s.client, "STOP", 0);
    WaitIdle(s.client, s.options);
    ExpectCode(s.client, "MOVE " + std::to_string(std::llround(lim.slide_min_mm * 100)) + ",0,0",
               0);
    WaitIdle(s.client, s.options);
  });
}

void TriggerChecks(Suite& s) {
  s.Run("trigger-order", "5 TRIG:PER before a wider TRIG:WIDT", [&] {
    ExpectCode(s.client, "TRIG:PER 20000", 0);
    ExpectCode(s.client, "TRIG:WIDT 15000", 0);
    ExpectCode(s.client, "TRIG:WIDT 20000", -222);
    ExpectCode(s.client, "TRIG:WIDT 100", 0);
    ExpectCode(s.client, "TRIG:PER 1000", 0);
    ExpectCode(s.client, "TRIG:COUN 1", 0);
  });
  s.Run("retransmission", "2 same line twice: executed once", [&] {
    const std::uint64_t before = s.client.Pulses().total;
    RawLink raw(s.transport, s.options);
    const std::string line = EncodeRequest(9991, "TRIG:FIRE");
    const std::optional<Reply> first = raw.Send(line);
    const std::optional<Reply> second = raw.Send(line);
    Expect(first && second && first->ok && second->ok, "TRIG:FIRE not answered OK twice");
    const std::uint64_t after = s.client.WaitTriggerDone();
    Expect(after == before + 1, std::to_string(after - before) + " pulses for one FIRE");
  });
  s.Run("link-loss", "7c SYST:WDOG: IRED off when the link is lost", [&] {
    s.client.DrainErrors();
    ExpectCode(s.client, "SYST:WDOG 1", 0);
    s.client.SetCurrent(100.0);
    std::this_thread::sleep_for(std::chrono::milliseconds(1500));  // > 1 s without a request
    const double measured_ma = s.client.MeasureCurrent();
    bool queued = false;
    for (const StationErrorEntry& e : s.client.DrainErrors()) queued = queued || e.code == 206;
    s.client.SetCurrent(0.0);
    Expect(measured_ma < 1.0, "IRED still at " + std::to_string(measured_ma) + " mA");
    Expect(queued, "error 206 not queued");
    ExpectCode(s.client, "SYST:WDOG 0", 0);
  });
  s.Run("current", "5 SOUR:CURR / MEAS:CURR?", [&] {
    s.client.SetCurrent(100.0);
    const double measured_ma = s.client.MeasureCurrent();
    s.client.SetCurrent(0.0);
    Expect(std::fabs(measured_ma - 100.0) <= 1.0,
           "measured " + std::to_string(measured_ma) + " mA at 100 mA set");
  });
}

}  // namespace

int ConformanceReport::Failures() const {
  int failures = 0;
  for (const ConformanceCheck& c : checks) failures += c.passed ? 0 : 1;
  return failures;
}

std::string ConformanceReport::Table() const {
  std::ostringstream out;
  for (const ConformanceCheck& c : checks) {
    char line[160];
    std::snprintf(line, sizeof(line), "%-4s  %-22s  %s", c.passed ? "PASS" : "FAIL",
                  c.name.c_str(), c.section.c_str());
    out << line << (c.passed ? "" : "\n      " + c.detail) << "\n";
  }
  out << checks.size() - static_cast<std::size_t>(Failures()) << "/" << checks.size()
      << " checks passed\n";
  return out.str();
}

bool ConformanceOptions::IsValid(std::string* why) const {
  std::string reason;
  if (reply_timeout.count() <= 0) {
    reason = "reply_timeout must be > 0";
  } else if (move_timeout.count() <= 0) {
    reason = "move_timeout must be > 0";
  } else if (poll_period.count() < 0) {
    reason = "poll_period must be >= 0";
  }
  if (why != nullptr) *why = reason;
  return reason.empty();
}

ConformanceReport RunConformance(Transport& transport, const ConformanceOptions& options) {
  std::string why;
  IRDIST_CHECK(options.IsValid(&why), "ConformanceOptions: " + why);
  ClientOptions client_options;
  client_options.reply_timeout = options.reply_timeout;
  client_options.move_timeout = options.move_timeout;
  client_options.poll_period = options.poll_period;
  client_options.recover_on_reboot = false;
  StationClient client(transport, client_options);
  client.Identify();  // a board that does not answer: LinkError
  Suite suite{transport, client, options, {}};
  IdentityChecks(suite);
  EStopChecks(suite);
  MotionChecks(suite);
  TriggerChecks(suite);
  try {
    client.SetCurrent(0.0);
  } catch (const Error&) {
    // Reported by the checks already.
  }
  return suite.report;
}

}  // namespace irdist
