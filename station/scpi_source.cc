// The SCPI current source driver (docs/devices/scpi_source.md): an IEEE 488.2 / SCPI SourceMeter
// with the Keithley 2400-series command set as the IRED's current source. Written from the
// "Series 2400 SourceMeter User's Manual" (SCPI command reference, status structure, RS-232
// interface) and IEEE 488.2 (*IDN?, *RST, the error queue).
//
// SCPI replies carry no request id: a reply is matched to its query by position in the stream.
// After a lost reply the stream is resynchronised with *IDN? (whose answer is known after
// Identify) before anything else is read, so a late reply is never taken for another's.

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "base/bounds.h"
#include "station/driver.h"
#include "station/serial_driver.h"
#include "station/line_query.h"

namespace irdist {
namespace {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

constexpr char kName[] = "scpi_source";
constexpr int kMaxErrorsRead = 32;  // the 2400's error queue holds 10; more = a stuck queue
constexpr double kNan = 9.9e37;     // manual, FORMat:ELEMents: "NAN" reads as +9.91e37
constexpr double kConfirmFraction = 0.01;  // a reading this far from the set-point is re-read
// A level read back within this of the one sent is the one sent: the 2400's coarsest source
// programming resolution is 50 uA (1 A range); levels a run sets differ by milliamps.
constexpr double kLevelReadbackA = 60e-6;
constexpr int kReadbackAttempts = 6;  // late answers to earlier queries read past before giving up

std::string Upper(std::string s) {
  for (char& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

std::string Trim(const std::string& s) {
  const std::size_t b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t\r") - b + 1);
}

std::vector<std::string> SplitCommas(const std::string& s) {
  std::vector<std::string> out;
  std::string cur;
  std::istringstream in(s);
  while (std::getline(in, cur, ',')) out.push_back(Trim(cur));
  return out;
}

bool ParseDouble(const std::string& text, double* value) {
  char* end = nullptr;
  *value = std::strtod(text.c_str(), &end);
  return !text.empty() && end == text.c_str() + text.size() && std::isfinite(*value);
}

class ScpiSource : public DeviceDriver, public CurrentSource {
 public:
  ScpiSource(const DeviceSpec& spec, std::unique_ptr<Transport> link)
      : spec_(spec), link_(std::move(link)), query_(link_.get(), QueryOptions(spec)) {
    identity_.kind = kName;
    identity_.port = spec.port;
    timeout_ = query_.options().reply_timeout;
    compliance_v_ = spec.Number("compliance_v", 0.0);
    reset_wait_ = milliseconds(static_cast<long long>(spec.Number("reset_wait_s", 60) * 1000));
  }
  ~ScpiSource() override {
    // Never write to a device that was not identified; `irdist station` leaves the output on.
    if (!idn_.empty() && !keep_output_) Off();
  }

  CurrentSource* source() override { return this; }

  DeviceIdentity Identify() override;
  void SetCurrent(double bias_ma) override;
  double setpoint_ma() const override { return setpoint_ma_; }
  SourceReading Measure() override;
  void Off() noexcept override;
  void CheckAlive() override;
  void KeepOutput() override { keep_output_ = true; }

 private:
  LineQueryOptions QueryOptions(const DeviceSpec& spec);
  std::string Query(const std::string& query,
                    const std::function<bool(const std::string&)>& valid);
  bool QueryBool(const std::string& query);
  bool QueryBoolConfirmed(const std::string& query, bool alarming);
  bool AdoptOutput();
  SourceReading ReadOnce();
  void Set(const std::string& command);
  void ReadBack(const std::string& query, const std::function<bool(const std::string&)>& is_answer,
                const std::function<bool(const std::string&)>& taken, const std::string& what);
  void ConfirmLevel(double amps);
  void DrainErrors(const std::string& after);
  void Resync();
  [[noreturn]] void WaitOutSilence(const NoReplyError& silent);
  void CheckIdentity(const std::string& idn);
  void ApplySourceSettings();
  bool OutputOn() { return QueryBool(":OUTP?"); }
  bool OutputOnConfirmed(bool alarming) { return QueryBoolConfirmed(":OUTP?", alarming); }
  void CheckOutputState();
  [[noreturn]] void Fail(const std::string& code, const std::string& message,
                         const std::string& fix) const {
    throw DeviceError(identity_, code, message, fix);
  }

  DeviceSpec spec_;
  std::unique_ptr<Transport> link_;
  LineQuery query_;  // after link_: it writes and reads through it
  DeviceIdentity identity_;
  std::string idn_;  // the full *IDN? answer, the resynchronisation marker
  milliseconds timeout_{1000};
  milliseconds reset_wait_{60000};  // an identified instrument silent this long is gone
  bool waiting_out_silence_ = false;
  double compliance_v_ = 0.0;
  double setpoint_ma_ = 0.0;
  bool output_on_ = false;
  bool out_of_step_ = false;  // a reply was lost: resynchronise before the next query
  bool keep_output_ = false;  // irdist station: an output found on is kept, and left on at exit
};

LineQueryOptions ScpiSource::QueryOptions(const DeviceSpec& spec) {
  LineQueryOptions options = QueryOptionsOf(
      spec, 3, 1000, "the SourceMeter",
      "check the RS-232 cable (straight-through), the baud rate, and that the instrument's "
      "terminator is LF");
  options.before_send = [this](int attempt) {
    if (attempt > 0 || out_of_step_) Resync();
  };
  options.after_miss = [this] { out_of_step_ = true; };  // a late or stray reply may still come
  return options;
}

// Sends a query and returns the first line, trimmed, if `valid` accepts it. A lost or invalid
// reply is retried (queries change nothing) after a resynchronisation.
std::string ScpiSource::Query(const std::string& query,
                              const std::function<bool(const std::string&)>& valid) {
  LineRequest request;
  request.query = query;
  request.judge = [&valid](const std::string& line) {
    return valid(Trim(line)) ? ReplyVerdict::kMatch : ReplyVerdict::kRetry;
  };
  try {
    return Trim(query_.Ask(request));
  } catch (const NoReplyError& silent) {
    if (idn_.empty() || waiting_out_silence_) throw;  // before Identify: no instrument there
    WaitOutSilence(silent);
  }
}

// Silent through every attempt once identified: the instrument may be starting after a power cut
// (the 2400 prints nothing while it does). *IDN? is asked until its known answer comes back, up to
// reset_wait_s (another instrument's answer never counts). What was sent meanwhile is lost, so the
// instrument's state is unknown: a DeviceRestarted, after which the settings and the level are
// set again (its output state read again first).
void ScpiSource::WaitOutSilence(const NoReplyError& silent) {
  const auto start = Clock::now();
  std::string heard;
  while (Clock::now() - start < reset_wait_) {
    link_->Flush();
    link_->WriteLine("*IDN?");
    std::string line;
    try {
      line = Trim(link_->ReadLine(timeout_));
    } catch (const LinkError&) {
      continue;  // still silent
    }
    if (line != idn_) {
      if (!line.empty()) heard = line;
      continue;
    }
    out_of_step_ = true;  // more answers to *IDN? may follow
    const auto silent_ms = std::chrono::duration_cast<milliseconds>(Clock::now() - start);
    waiting_out_silence_ = true;  // silent again now: a LinkError, no second wait
    try {
      output_on_ = OutputOnConfirmed(false);
    } catch (...) {
      waiting_out_silence_ = false;
      throw;
    }
    waiting_out_silence_ = false;
    if (!output_on_) setpoint_ma_ = 0.0;
    throw DeviceRestarted(identity_.Brief() + ": silent for " + std::to_string(silent_ms.count()) +
                              " ms after '" + silent.query() + "', then it answered again: it "
                              "was power-cycled or reset and what was sent meanwhile is lost; "
                              "the IRED current must be set again",
                          false);
  }
  throw LinkError("the SourceMeter silent for reset_wait_s (" +
                      std::to_string(reset_wait_.count()) + " ms) after '" + silent.query() +
                      "'" + (heard.empty() ? "" : " (heard '" + heard + "', not its *IDN?)"),
                  spec_.port,
                  "check the instrument's power and RS-232 cable; an instrument that takes "
                  "longer to start needs a larger reset_wait_s");
}

// Reads away whatever is pending until the known *IDN? answer comes back. Silence is waited
// through to the deadline: a late answer to an earlier query may still be on its way, and
// stopping at the first quiet read would leave it to be taken as the next query's answer.
void ScpiSource::Resync() {
  link_->Flush();
  if (idn_.empty()) {  // before Identify: nothing known to wait for
    out_of_step_ = false;
    return;
  }
  link_->WriteLine("*IDN?");
  const auto deadline = Clock::now() + timeout_ * 2;
  for (auto left = timeout_ * 2; left.count() > 0;
       left = std::chrono::duration_cast<milliseconds>(deadline - Clock::now())) {
    try {
      if (Trim(link_->ReadLine(left)) == idn_) {
        out_of_step_ = false;
        return;
      }
    } catch (const LinkError&) {
      // nothing within `left`: the loop ends at the deadline, still out of step
    }
  }
}

bool ScpiSource::QueryBool(const std::string& query) {
  const std::string reply =
      Query(query, [](const std::string& r) { return r == "0" || r == "1"; });
  return reply == "1";
}

// A reply that would stop a run (`alarming`) is read a second time: SCPI has no checksum, and one
// flipped bit turns "1" into "0". The second reading decides.
bool ScpiSource::QueryBoolConfirmed(const std::string& query, bool alarming) {
  const bool first = QueryBool(query);
  return first == alarming ? QueryBool(query) : first;
}

// irdist station: an output found on, sourcing current, is taken as it is (nothing reset); its
// level becomes the set-point. False when the output is off or sources voltage.
bool ScpiSource::AdoptOutput() {
  if (!OutputOnConfirmed(false)) return false;
  const std::string function = Upper(Query(":SOUR:FUNC?", [](const std::string& r) {
    return !r.empty() && r.find(',') == std::string::npos;
  }));
  if (function.rfind("CURR", 0) != 0) return false;
  const std::string level = Query(":SOUR:CURR:LEV?", [](const std::string& r) {
    double v = 0;
    return ParseDouble(r, &v);
  });
  double amps = 0.0;
  ParseDouble(level, &amps);
  output_on_ = true;
  setpoint_ma_ = amps * 1000.0;
  return true;
}

// A setting: sent once (never repeated blindly), then the error queue is read (manual: the
// 2400 reports a refused command only through the error queue).
void ScpiSource::Set(const std::string& command) {
  link_->WriteLine(command);
  DrainErrors(command);
}

// Reads :SYST:ERR? until "0,..."; any error becomes a DeviceError naming the command.
void ScpiSource::DrainErrors(const std::string& after) {
  std::string first;
  for (int i = 0; i < kMaxErrorsRead; ++i) {
    const std::string reply = Query(":SYST:ERR?", [](const std::string& r) {
      const std::size_t comma = r.find(',');
      double code = 0;
      return comma != std::string::npos && ParseDouble(Trim(r.substr(0, comma)), &code);
    });
    double code = 0.0;  // the judge above accepted it as a number; any value but 0 is an error
    ParseDouble(Trim(reply.substr(0, reply.find(','))), &code);
    if (code == 0.0) break;
    if (first.empty()) first = reply;
  }
  if (!first.empty()) {
    Fail(first, "refused '" + after + "'",
         "check the command against the 2400 manual's SCPI reference and the value's range");
  }
}

void ScpiSource::CheckIdentity(const std::string& idn) {
  const std::vector<std::string> f = SplitCommas(idn);
  if (f.size() < 4) {
    Fail(idn, "the device on this port answered *IDN? with '" + idn +
                  "', not an IEEE 488.2 identity (maker,model,serial,firmware)",
         "check that the port is the SourceMeter's (ls -l /dev/serial/by-id) and its baud rate");
  }
  identity_.vendor = f[0];
  identity_.model = f[1];
  identity_.serial = f[2];
  identity_.firmware = f[3];
  const std::string vendor = spec_.Text("idn_vendor", "KEITHLEY");
  const std::string model = spec_.Text("idn_model", "MODEL 24");
  if (Upper(f[0]).find(Upper(vendor)) == std::string::npos ||
      Upper(f[1]).find(Upper(model)) == std::string::npos) {
    Fail(idn, "the device on this port is '" + f[0] + " " + f[1] + "', not a '" + vendor + " " +
                  model + "..' SourceMeter",
         "connect the SourceMeter to this port, or set idn_vendor/idn_model in the rig file if "
         "this instrument really speaks the 2400 command set");
  }
  const std::string serial = spec_.Text("serial", "");
  if (!serial.empty() && serial != f[2]) {
    Fail(f[2], "serial " + f[2] + " is not the rig file's " + serial,
         "two instruments may be swapped: check /dev/serial/by-id");
  }
}

// Manual: current source, fixed level, voltage compliance; output off.
void ScpiSource::ApplySourceSettings() {
  char level[64];
  std::snprintf(level, sizeof(level), ":SENS:VOLT:PROT %.6g", compliance_v_);
  Set(":SOUR:FUNC CURR");
  Set(level);
  Set(":SOUR:CURR:LEV 0");
}

DeviceIdentity ScpiSource::Identify() {
  link_->Flush();
  std::string idn;
  try {
    idn = Query("*IDN?", [](const std::string& r) { return !r.empty(); });
  } catch (const LinkError& e) {
    Fail("", std::string("no answer to *IDN?: ") + e.what(),
         "check that the port is the SourceMeter's, its RS-232 baud rate and terminator (LF)");
  }
  CheckIdentity(idn);
  idn_ = idn;
  link_->WriteLine("*CLS");  // IEEE 488.2: empties the error queue of older sessions
  if (keep_output_ && AdoptOutput()) return identity_;  // irdist station: left as it was
  link_->WriteLine("*RST");  // manual: output off, power-on defaults
  DrainErrors("*RST");
  ApplySourceSettings();
  Set(":OUTP OFF");
  output_on_ = false;
  setpoint_ma_ = 0.0;
  return identity_;
}

void ScpiSource::SetCurrent(double bias_ma) {
  if (!(bias_ma > 0.0)) {
    Set(":OUTP OFF");
    output_on_ = false;
    setpoint_ma_ = 0.0;
    Set(":SOUR:CURR:LEV 0");
    return;
  }
  char level[64];
  std::snprintf(level, sizeof(level), ":SOUR:CURR:LEV %.6E", bias_ma / 1000.0);
  if (!output_on_) ApplySourceSettings();  // a power cycle while off loses them silently
  Set(level);
  ConfirmLevel(bias_ma / 1000.0);
  setpoint_ma_ = bias_ma;
  if (!output_on_) {
    Set(":OUTP ON");
    ReadBack(":OUTP?", [](const std::string& r) { return r == "0" || r == "1"; },
             [](const std::string& r) { return r == "1"; }, "the output switched on");
    output_on_ = true;
  }
}

// Asks `query` until its answer shows the change (`taken`). The instrument takes commands in
// order, so an answer showing it answers a query sent after the command; a late answer to an
// earlier query shows the old state and is read past, after a resynchronisation. Until then the
// change has not happened as far as anyone can tell, and no frame may be exposed.
void ScpiSource::ReadBack(const std::string& query,
                          const std::function<bool(const std::string&)>& is_answer,
                          const std::function<bool(const std::string&)>& taken,
                          const std::string& what) {
  std::string heard;
  for (int attempt = 0; attempt < kReadbackAttempts; ++attempt) {
    heard = Query(query, is_answer);
    if (taken(heard)) return;
    out_of_step_ = true;  // perhaps a late answer: read past what is pending before asking again
  }
  Fail(heard, "not taken: " + what + ", yet '" + query + "' still answers '" + heard + "'",
       "check the front panel (interlock, REM/LOCAL, a menu left open) and the value's range; "
       "then restart the run");
}

void ScpiSource::ConfirmLevel(double amps) {
  const auto is_number = [](const std::string& r) {
    double v = 0;
    return ParseDouble(r, &v);
  };
  const auto is_level = [amps](const std::string& r) {
    double v = 0;
    return ParseDouble(r, &v) && std::abs(v - amps) <= kLevelReadbackA;
  };
  char what[64];
  std::snprintf(what, sizeof(what), "the level set to %.6E A", amps);
  ReadBack(":SOUR:CURR:LEV?", is_number, is_level, what);
}

// Output found off while it should be on: a power cycle (source function back to its power-on
// default) or a trip (interlock, over-temperature: settings kept).
void ScpiSource::CheckOutputState() {
  if (!output_on_ || OutputOnConfirmed(false)) return;
  const std::string function = Upper(Query(":SOUR:FUNC?", [](const std::string& r) {
    return !r.empty() && r.find(',') == std::string::npos;
  }));
  const double set_ma = setpoint_ma_;
  output_on_ = false;
  setpoint_ma_ = 0.0;
  if (function.rfind("CURR", 0) != 0) {
    throw DeviceRestarted(identity_.Brief() + ": the output is off and the source function is " +
                              function + ": the instrument was power-cycled or reset; the IRED "
                              "current (" + std::to_string(set_ma) + " mA) must be set again",
                          false);
  }
  Fail("OUTP 0", "the output switched off by itself while sourcing " + std::to_string(set_ma) +
                     " mA", "check the interlock, over-temperature and the front panel; then "
                     "restart the run");
}

// One :READ?. Manual, FORMat:ELEMents: the answer is VOLT,CURR,RES,TIME,STAT (those enabled);
// the current is the second element in the default format, in amperes.
SourceReading ScpiSource::ReadOnce() {
  const std::string data = Query(":READ?", [](const std::string& r) {
    const std::vector<std::string> f = SplitCommas(r);
    double v = 0;
    return f.size() >= 2 && ParseDouble(f[0], &v) && ParseDouble(f[1], &v);
  });
  const std::vector<std::string> f = SplitCommas(data);
  double volts = 0, amps = 0;
  ParseDouble(f[0], &volts);
  ParseDouble(f[1], &amps);
  SourceReading reading;
  reading.voltage_v = volts >= kNan ? 0.0 : volts;
  reading.current_ma = amps >= kNan ? 0.0 : amps * 1000.0;
  reading.output_on = true;
  return reading;
}

SourceReading ScpiSource::Measure() {
  CheckOutputState();
  if (!output_on_) return SourceReading{};
  SourceReading reading = ReadOnce();
  // SCPI replies carry no checksum: a reading away from the set-point is confirmed by a second
  // one (a real mismatch persists, a damaged digit does not).
  if (std::abs(reading.current_ma - setpoint_ma_) > kConfirmFraction * setpoint_ma_) {
    reading = ReadOnce();
  }
  reading.in_compliance = QueryBoolConfirmed(":SENS:VOLT:PROT:TRIP?", true);
  return reading;
}

// Writes :OUTP OFF, then reads :OUTP? once (no retries: exit paths must stay quick) and writes
// it again if the output still reads on (the first one damaged on the wire).
void ScpiSource::Off() noexcept {
  output_on_ = false;
  setpoint_ma_ = 0.0;
  try {
    link_->WriteLine(":OUTP OFF");
    link_->Flush();
    link_->WriteLine(":OUTP?");
    if (Trim(link_->ReadLine(timeout_)) != "0") link_->WriteLine(":OUTP OFF");
  } catch (...) {
    // Best effort on every exit path: nothing more can be done over a dead link.
  }
  out_of_step_ = true;  // whatever is still in flight is not the next query's answer
}

void ScpiSource::CheckAlive() {
  CheckOutputState();
  if (!output_on_ && OutputOnConfirmed(true)) {
    Fail("OUTP 1", "the output is on while irdist set it off",
         "someone is driving the instrument from elsewhere (front panel, another program)");
  }
}

[[noreturn]] void Invalid(const DeviceSpec& spec, const std::string& message) {
  InvalidEntry(spec, kName, message);
}

void Validate(const DeviceSpec& spec) {
  spec.CheckKnown({"compliance_v", "idn_vendor", "idn_model", "serial", "retries",
                   "reset_wait_s"});
  if (!spec.axes.empty()) Invalid(spec, "a current source drives no axes: remove `axes:`");
  if (!spec.settings.count("compliance_v")) {
    Invalid(spec, "compliance_v (the voltage limit while sourcing current) is required: the "
                  "IRED's maximum forward voltage plus the leads' drop");
  }
  const double v = spec.Number("compliance_v", 0.0);
  if (!(v > 0.0 && v <= 210.0)) Invalid(spec, "compliance_v must be in (0, 210] V");
  const double retries = spec.Number("retries", 3);
  if (retries < 0 || retries > 10) Invalid(spec, "retries must be 0-10");
  const std::string reset_wait = bounds::kDurationS.Refusal("reset_wait_s",  // in ms later
                                                            spec.Number("reset_wait_s", 60));
  if (!reset_wait.empty()) Invalid(spec, reset_wait);
}

// Lines end with "\n" (the instrument's RS-232 terminator must be set to LF); 9600 baud,
// replies within 1000 ms.
DriverInfo MakeScpiInfo() {
  return SerialDriverInfo<ScpiSource>(kName, "\n", 9600, 1000, {"source"}, Validate);
}

}  // namespace

IRDIST_REGISTER_DRIVER(scpi_source, MakeScpiInfo());

}  // namespace irdist
