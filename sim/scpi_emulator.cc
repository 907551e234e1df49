// The emulator of a Keithley 2400-class SourceMeter driven by SCPI over its RS-232 port (driver
// `scpi_source`), written from the public "Series 2400 SourceMeter User's Manual" (SCPI command
// reference, data elements of :READ?/:MEASure?, status word, error queue) and IEEE 488.2 (common
// commands, header syntax). It sources current (or voltage) into an IRED modelled as a forward
// voltage plus a series resistance, so compliance is physical: when the load needs more voltage
// than the compliance limit, the voltage sits at the limit and less current flows.
//
// Syntax: a message ends with LF (CR LF accepted); units are separated by ';'; headers match in
// their long or short form, case-insensitive, with [optional] nodes; a query ends with '?';
// several queries in one message answer in one line joined by ';'. Errors go to the error
// queue (10 entries; overflow replaces the last with -350) read by :SYSTem:ERRor?.

#include "sim/scpi_emulator.h"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <deque>
#include <sstream>

#include "base/check.h"
#include "sim/line_device.h"

namespace irdist::sim {

bool SourceFaults::IsValid(std::string* why) const {
  if (!std::isfinite(extra_resistance_ohm) || extra_resistance_ohm < 0) {
    if (why) *why = "extra_resistance_ohm must be >= 0";
    return false;
  }
  if (!std::isfinite(trip_after_s)) {
    if (why) *why = "trip_after_s must be finite";
    return false;
  }
  return true;
}

namespace {

constexpr double kNotANumber = 9.91e37;  // the SourceMeter's NAN reading
// Status word bits (2400 manual, data elements): compliance, V and I measured, I sourced.
constexpr unsigned kStatusCompliance = 1u << 3;
constexpr unsigned kStatusVoltMeasured = 1u << 11;
constexpr unsigned kStatusCurrMeasured = 1u << 12;
constexpr unsigned kStatusCurrSourced = 1u << 15;

struct ScpiConfig {
  std::string model = "MODEL 2400";
  std::string serial = "4312345";
  std::string firmware = "C32   Oct  4 2010 14:20:11/A02  /S/K";
  double forward_voltage_v = 1.6;      // IRED knee
  double series_resistance_ohm = 1.5;  // IRED + leads
  double max_current_a = 1.05;         // source range
  double max_voltage_v = 21.0;
  double reset_s = 0.0;  // a power cycle's boot (self-test): deaf and silent, as the 2400 is
};

struct SourceState {
  bool output_on = false;
  bool source_current = false;  // *RST: voltage source
  double current_a = 0.0, voltage_v = 0.0;
  double volt_protection_v = 21.0, curr_protection_a = 105e-6;
  bool auto_off = false;  // :SOURce:CLEar:AUTO
  std::vector<std::string> elements{"VOLT", "CURR", "RES", "TIME", "STAT"};
  double output_on_since_s = 0.0;
};

struct Reading {
  double voltage_v = 0.0, current_a = 0.0;
  bool compliance = false;
};

// One header keyword of a pattern: "CURRent" -> long "CURRENT", short "CURR".
struct Keyword {
  std::string long_form, short_form;
  bool optional = false;
};

std::vector<Keyword> ParsePattern(const std::string& pattern) {
  std::vector<Keyword> keywords;
  std::size_t i = 0;
  while (i < pattern.size()) {
    Keyword k;
    if (pattern[i] == '[') {
      k.optional = true;
      ++i;
    }
    if (pattern[i] == ':') ++i;
    while (i < pattern.size() && std::isalpha(static_cast<unsigned char>(pattern[i]))) {
      const char c = pattern[i++];
      k.long_form += static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
      if (std::isupper(static_cast<unsigned char>(c))) k.short_form += c;
    }
    if (i < pattern.size() && pattern[i] == ']') ++i;
    keywords.push_back(k);
  }
  return keywords;
}

bool MatchFrom(const std::vector<Keyword>& pattern, std::size_t p,
               const std::vector<std::string>& words, std::size_t w) {
  if (p == pattern.size()) return w == words.size();
  const Keyword& k = pattern[p];
  if (w < words.size() && (words[w] == k.long_form || words[w] == k.short_form) &&
      MatchFrom(pattern, p + 1, words, w + 1)) {
    return true;
  }
  return k.optional && MatchFrom(pattern, p + 1, words, w);
}

bool HeaderMatches(const std::string& pattern, const std::vector<std::string>& words) {
  return MatchFrom(ParsePattern(pattern), 0, words, 0);
}

std::string Upper(std::string text) {
  for (char& c : text) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return text;
}

std::string Trim(const std::string& text) {
  const std::size_t a = text.find_first_not_of(" \t");
  if (a == std::string::npos) return "";
  return text.substr(a, text.find_last_not_of(" \t") - a + 1);
}

std::string Number(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%+.6E", value);
  return text;
}

// Settings of the real instrument this model has no use for (ranges, integration time, display,
// beeper, trigger counts...): accepted without an error so that a driver's usual set-up passes.
bool AcceptedWithoutEffect(const std::vector<std::string>& words) {
  static const char* const kPatterns[] = {
      "SENSe:FUNCtion[:ON]",           "SENSe:FUNCtion:CONCurrent",
      "SENSe:CURRent[:DC]:RANGe[:UPPer]", "SENSe:CURRent[:DC]:RANGe:AUTO",
      "SENSe:VOLTage[:DC]:RANGe[:UPPer]", "SENSe:VOLTage[:DC]:RANGe:AUTO",
      "SENSe:CURRent[:DC]:NPLCycles",  "SENSe:VOLTage[:DC]:NPLCycles",
      "SOURce:CURRent:RANGe[:UPPer]",  "SOURce:CURRent:RANGe:AUTO",
      "SOURce:VOLTage:RANGe[:UPPer]",  "SOURce:VOLTage:RANGe:AUTO",
      "SOURce:CURRent:MODE",           "SOURce:VOLTage:MODE",
      "SOURce:DELay",                  "SOURce:DELay:AUTO",
      "SYSTem:REMote",                 "SYSTem:LOCal",
      "SYSTem:RSENse",                 "SYSTem:AZERo[:STATe]",
      "SYSTem:BEEPer:STATe",           "DISPlay:ENABle",
      "FORMat:DATA",                   "TRIGger:COUNt",
      "ARM:COUNt",                     "INITiate",
      "STATus:PRESet",                 "OUTPut:SMODe"};
  for (const char* pattern : kPatterns) {
    if (HeaderMatches(pattern, words)) return true;
  }
  return false;
}

class ScpiEmulator : public LineDevice {
 public:
  ScpiEmulator(World& world, const EmulatorSpec& spec, const DeviceKeys& keys, ScpiConfig config,
               SourceFaults source_faults)
      : LineDevice(world, spec.name, keys.faults, spec.seed),
        config_(std::move(config)),
        source_faults_(source_faults) {
    SetReplyBitFlip(keys.flip);
    std::lock_guard<std::mutex> lock(state_mutex_);
    ResetToPowerOn();
  }

  void SetSourceFaults(const SourceFaults& faults) {
    std::string why;
    IRDIST_CHECK(faults.IsValid(&why), "scpi_source: " + why);
    std::lock_guard<std::mutex> lock(state_mutex_);
    source_faults_ = faults;
    Advance(Now());
  }

  // The serving thread calls this class's hooks: stop it before the members go.
  ~ScpiEmulator() override { Stop(); }

 protected:
  std::string Terminators() const override { return "\r\n"; }
  std::string HandleMessage(const std::string& message) override;
  void Advance(double now_s) override;
  void ResetToPowerOn() override;
  double BootSeconds() const override { return config_.reset_s; }

 private:
  // A unit's outcome: a reply for a query, or nothing; errors are queued.
  std::optional<std::string> Unit(const std::string& unit);
  std::optional<std::string> Common(const std::string& header, bool query);
  std::optional<std::string> Subsystem(const std::vector<std::string>& words, bool query,
                                       const std::string& argument);
  std::optional<std::string> Measure(bool reading_only);
  std::optional<std::string> SetNumber(double* target, const std::string& argument, double low,
                                       double high);
  std::optional<std::string> SetOutput(const std::string& argument);
  std::optional<std::string> SetElements(const std::string& argument);
  std::optional<std::string> SetFunction(const std::string& argument);
  std::string Elements() const;
  Reading Solve() const;
  void PushError(int code, const std::string& text);
  std::string PopError();
  void WriteCurrentToWorld();

  ScpiConfig config_;
  SourceFaults source_faults_;
  SourceState state_;
  std::deque<std::string> errors_;
  double powered_on_s_ = 0.0;
  double world_current_ma_ = -1.0;
};

void ScpiEmulator::ResetToPowerOn() {
  state_ = SourceState();
  errors_.clear();
  powered_on_s_ = Now();
  WriteCurrentToWorld();
}

void ScpiEmulator::PushError(int code, const std::string& text) {
  const std::string entry = std::to_string(code) + ",\"" + text + "\"";
  if (errors_.size() >= 10) {
    errors_.back() = "-350,\"Queue overflow\"";
    return;
  }
  errors_.push_back(code > 0 ? "+" + entry : entry);
}

std::string ScpiEmulator::PopError() {
  if (errors_.empty()) return "0,\"No error\"";
  std::string entry = errors_.front();
  errors_.pop_front();
  return entry;
}

Reading ScpiEmulator::Solve() const {
  const double vf = config_.forward_voltage_v;
  const double r = config_.series_resistance_ohm + source_faults_.extra_resistance_ohm;
  Reading out;
  if (state_.source_current) {
    const double limit_v = state_.volt_protection_v;
    const double wanted_a = std::max(0.0, state_.current_a);  // the IRED blocks reverse current
    if (source_faults_.open_circuit || state_.current_a < 0) {
      out = {state_.current_a == 0 ? 0.0 : std::copysign(limit_v, state_.current_a), 0.0,
             state_.current_a != 0};
      return out;
    }
    const double needed_v = wanted_a > 0 ? vf + r * wanted_a : 0.0;
    if (needed_v <= limit_v) return {needed_v, wanted_a, false};
    return {limit_v, std::max(0.0, (limit_v - vf) / r), true};
  }
  const double v = state_.voltage_v;
  const double flowing_a = source_faults_.open_circuit ? 0.0 : std::max(0.0, (v - vf) / r);
  if (flowing_a <= state_.curr_protection_a) return {v, flowing_a, false};
  return {vf + r * state_.curr_protection_a, state_.curr_protection_a, true};
}

void ScpiEmulator::WriteCurrentToWorld() {
  const double ma = state_.output_on ? Solve().current_a * 1000.0 : 0.0;
  if (ma == world_current_ma_) return;
  world_current_ma_ = ma;
  world().SetCurrent(ma);
}

void ScpiEmulator::Advance(double now_s) {
  if (state_.output_on && source_faults_.trip_after_s >= 0 &&
      now_s - state_.output_on_since_s >= source_faults_.trip_after_s) {
    state_.output_on = false;  // tripped: the output switches itself off
    PushError(-300, "Device-specific error; output tripped");
  }
  WriteCurrentToWorld();
}

std::string ScpiEmulator::HandleMessage(const std::string& message) {
  std::vector<std::string> units;
  std::string unit;
  bool quoted = false;
  for (char c : message) {
    if (c == '"') quoted = !quoted;
    if (c == ';' && !quoted) {
      units.push_back(unit);
      unit.clear();
    } else {
      unit += c;
    }
  }
  units.push_back(unit);
  std::string replies;
  for (const std::string& u : units) {
    if (Trim(u).empty()) continue;
    const std::optional<std::string> reply = Unit(Trim(u));
    if (reply) replies += (replies.empty() ? "" : ";") + *reply;
  }
  WriteCurrentToWorld();
  return replies.empty() ? "" : replies + "\n";
}

std::optional<std::string> ScpiEmulator::Unit(const std::string& unit) {
  const std::size_t space = unit.find_first_of(" \t");
  std::string header = Upper(unit.substr(0, space));
  const std::string argument = space == std::string::npos ? "" : Trim(unit.substr(space));
  const bool query = !header.empty() && header.back() == '?';
  if (query) header.pop_back();
  if (!header.empty() && header[0] == '*') return Common(header, query);
  if (!header.empty() && header[0] == ':') header.erase(0, 1);
  std::vector<std::string> words;
  std::string word;
  std::istringstream in(header);
  while (std::getline(in, word, ':')) words.push_back(word);
  return Subsystem(words, query, argument);
}

std::optional<std::string> ScpiEmulator::Common(const std::string& header, bool query) {
  if (header == "*IDN" && query) {
    return "KEITHLEY INSTRUMENTS INC.," + config_.model + "," + config_.serial + "," +
           config_.firmware;
  }
  if (header == "*RST" && !query) {
    state_ = SourceState();  // output off, voltage source, defaults; the error queue stays
    return std::nullopt;
  }
  if (header == "*CLS" && !query) {
    errors_.clear();
    return std::nullopt;
  }
  if (header == "*OPC" && query) return std::string("1");
  if ((header == "*OPC" || header == "*WAI") && !query) return std::nullopt;
  if (header == "*TST" && query) return std::string("0");
  PushError(-113, "Undefined header");
  return std::nullopt;
}

std::optional<std::string> ScpiEmulator::Subsystem(const std::vector<std::string>& words,
                                                   bool query, const std::string& argument) {
  const auto is = [&words](const char* pattern) { return HeaderMatches(pattern, words); };
  if (is("SYSTem:ERRor[:NEXT]") && query) return PopError();
  if (is("SOURce:FUNCtion[:MODE]")) {
    return query ? std::optional<std::string>(state_.source_current ? "CURR" : "VOLT")
                 : SetFunction(argument);
  }
  if (is("SOURce:CURRent[:LEVel][:IMMediate][:AMPLitude]")) {
    return query ? Number(state_.current_a)
                 : SetNumber(&state_.current_a, argument, -config_.max_current_a,
                             config_.max_current_a);
  }
  if (is("SOURce:VOLTage[:LEVel][:IMMediate][:AMPLitude]")) {
    return query ? Number(state_.voltage_v)
                 : SetNumber(&state_.voltage_v, argument, -config_.max_voltage_v,
                             config_.max_voltage_v);
  }
  if (is("SENSe:VOLTage[:DC]:PROTection[:LEVel]")) {
    return query ? Number(state_.volt_protection_v)
                 : SetNumber(&state_.volt_protection_v, argument, 0.2, config_.max_voltage_v);
  }
  if (is("SENSe:CURRent[:DC]:PROTection[:LEVel]")) {
    return query ? Number(state_.curr_protection_a)
                 : SetNumber(&state_.curr_protection_a, argument, 1e-9, config_.max_current_a);
  }
  if (is("SENSe:VOLTage[:DC]:PROTection:TRIPped") && query) {
    return std::string(state_.output_on && Solve().compliance ? "1" : "0");
  }
  if (is("OUTPut[:STATe]")) {
    return query ? std::optional<std::string>(state_.output_on ? "1" : "0") : SetOutput(argument);
  }
  if (is("FORMat:ELEMents[:SENSe]")) return query ? Elements() : SetElements(argument);
  if (is("READ") && query) return Measure(true);
  if ((is("MEASure[:CURRent][:DC]") || is("MEASure:VOLTage[:DC]")) && query) {
    return Measure(false);
  }
  if (!query && AcceptedWithoutEffect(words)) return std::nullopt;
  if (is("SYSTem:ERRor:COUNt") && query) return std::to_string(errors_.size());
  if (is("FETCh") && query) return Measure(true);
  if (is("SOURce:CLEar:AUTO") && !query) {
    const std::string value = Upper(argument);
    if (value != "ON" && value != "OFF" && value != "1" && value != "0") {
      PushError(-224, "Illegal parameter value");
    } else {
      state_.auto_off = value == "ON" || value == "1";
    }
    return std::nullopt;
  }
  PushError(-113, "Undefined header");
  return std::nullopt;
}

std::optional<std::string> ScpiEmulator::SetNumber(double* target, const std::string& argument,
                                                   double low, double high) {
  if (argument.empty()) {
    PushError(-109, "Missing parameter");
    return std::nullopt;
  }
  char* end = nullptr;
  const double value = std::strtod(argument.c_str(), &end);
  if (end == argument.c_str() || Trim(end) != "" || !std::isfinite(value)) {
    PushError(-104, "Data type error");
  } else if (value < low || value > high) {
    PushError(-222, "Data out of range");
  } else {
    *target = value;
  }
  return std::nullopt;
}

std::optional<std::string> ScpiEmulator::SetOutput(const std::string& argument) {
  const std::string value = Upper(argument);
  if (value == "ON" || value == "1") {
    if (!state_.output_on) state_.output_on_since_s = Now();
    state_.output_on = true;
    NoteMoveStarted();  // a source's "move": power_cycle_after_s counts from its first output on
  } else if (value == "OFF" || value == "0") {
    state_.output_on = false;
  } else {
    PushError(argument.empty() ? -109 : -224,
              argument.empty() ? "Missing parameter" : "Illegal parameter value");
  }
  return std::nullopt;
}

std::optional<std::string> ScpiEmulator::SetFunction(const std::string& argument) {
  const std::string value = Upper(argument);
  if (value == "CURR" || value == "CURRENT") {
    state_.source_current = true;
  } else if (value == "VOLT" || value == "VOLTAGE") {
    state_.source_current = false;
  } else {
    PushError(-224, "Illegal parameter value");
  }
  return std::nullopt;
}

std::optional<std::string> ScpiEmulator::SetElements(const std::string& argument) {
  std::vector<std::string> elements;
  std::istringstream in(Upper(argument));
  std::string item;
  while (std::getline(in, item, ',')) {
    item = Trim(item);
    const std::string name = item.substr(0, 4);
    if (name != "VOLT" && name != "CURR" && name != "RES" && name.substr(0, 3) != "RES" &&
        name != "TIME" && name != "STAT") {
      PushError(-224, "Illegal parameter value");
      return std::nullopt;
    }
    elements.push_back(name.substr(0, 3) == "RES" ? "RES" : name);
  }
  if (elements.empty()) {
    PushError(-109, "Missing parameter");
  } else {
    state_.elements = elements;
  }
  return std::nullopt;
}

std::string ScpiEmulator::Elements() const {
  std::string text;
  for (const std::string& e : state_.elements) text += (text.empty() ? "" : ",") + e;
  return text;
}

std::optional<std::string> ScpiEmulator::Measure(bool reading_only) {
  if (!state_.output_on) {
    if (reading_only) {
      PushError(803, "Output disabled");
      return std::nullopt;
    }
    state_.output_on = true;  // :MEASure? turns the output on (auto output-on)
    state_.output_on_since_s = Now();
  }
  const Reading r = Solve();
  unsigned status = kStatusVoltMeasured | kStatusCurrMeasured;
  if (state_.source_current) status |= kStatusCurrSourced;
  if (r.compliance) status |= kStatusCompliance;
  std::string text;
  for (const std::string& e : state_.elements) {
    const double value = e == "VOLT" ? r.voltage_v
                         : e == "CURR" ? r.current_a
                         : e == "RES"  ? kNotANumber
                         : e == "TIME" ? Now() - powered_on_s_
                                       : static_cast<double>(status);
    text += (text.empty() ? "" : ",") + Number(value);
  }
  if (!reading_only && state_.auto_off) state_.output_on = false;
  return text;
}

// ----------------------------------------------------------------------------------------------
// Construction from the rig file.

const std::vector<std::string> kScpiKeys = {
    "model",         "serial",          "firmware",     "forward_voltage_v",
    "series_resistance_ohm", "max_current_a", "max_voltage_v", "open_circuit",
    "extra_resistance_ohm",  "trip_after_s",  "reset_s"};

std::unique_ptr<DeviceEmulator> CreateScpi(World& world, const EmulatorSpec& spec) {
  const DeviceKeys keys = ReadDeviceKeys(spec, kScpiKeys);
  ScpiConfig c;
  c.model = keys.Text("model", c.model);
  c.serial = keys.Text("serial", c.serial);
  c.firmware = keys.Text("firmware", c.firmware);
  c.forward_voltage_v = keys.Number("forward_voltage_v", c.forward_voltage_v);
  c.series_resistance_ohm = keys.Number("series_resistance_ohm", c.series_resistance_ohm);
  c.max_current_a = keys.Number("max_current_a", c.max_current_a);
  c.max_voltage_v = keys.Number("max_voltage_v", c.max_voltage_v);
  if (!(c.forward_voltage_v >= 0)) keys.Fail("forward_voltage_v", "must be >= 0");
  if (!(c.series_resistance_ohm > 0)) keys.Fail("series_resistance_ohm", "must be > 0");
  if (!(c.max_current_a > 0)) keys.Fail("max_current_a", "must be > 0");
  if (!(c.max_voltage_v > 0.2)) keys.Fail("max_voltage_v", "must be > 0.2");
  c.reset_s = keys.Number("reset_s", c.reset_s);
  if (!(c.reset_s >= 0.0 && c.reset_s <= 86400.0)) keys.Fail("reset_s", "must be in [0, 86400] s");
  SourceFaults f;
  f.open_circuit = keys.Boolean("open_circuit", f.open_circuit);
  f.extra_resistance_ohm = keys.Number("extra_resistance_ohm", f.extra_resistance_ohm);
  f.trip_after_s = keys.Number("trip_after_s", f.trip_after_s);
  std::string why;
  if (!f.IsValid(&why)) keys.Fail("extra_resistance_ohm", why);
  return std::make_unique<ScpiEmulator>(world, spec, keys, c, f);
}

}  // namespace

void SetSourceFaults(DeviceEmulator& emulator, const SourceFaults& faults) {
  auto* source = dynamic_cast<ScpiEmulator*>(&emulator);
  IRDIST_CHECK(source != nullptr, "SetSourceFaults: the emulator is not a scpi_source");
  source->SetSourceFaults(faults);
}

IRDIST_REGISTER_EMULATOR(scpi_source, (EmulatorInfo{"scpi_source", &CreateScpi}));

}  // namespace irdist::sim
