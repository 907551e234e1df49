// The scpi_source driver against a scripted Keithley 2400 (replies shaped as the 2400 manual's:
// *IDN? "KEITHLEY INSTRUMENTS INC.,MODEL 2400,...", :READ? "V,I,R,T,STAT", :SYST:ERR? "0,...").

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <deque>
#include <functional>
#include <map>
#include <utility>

#include "base/input_error.h"
#include "sim/device_emulator.h"
#include "sim/world.h"
#include "station/driver.h"
#include "station/serial_transport.h"
#include "tests/station/fake_transport.h"
#include "tests/station/rig_fixture.h"

namespace irdist {
namespace {

constexpr char kIdn[] = "KEITHLEY INSTRUMENTS INC.,MODEL 2400,1234567,C30 Mar 17 2006 09:29:29/A02 /K/J";

struct SourceMeter {
  std::string idn = kIdn;
  std::string function = "VOLT";
  double level_a = 0.0, compliance_v = 21.0;
  bool output = false;
  double load_ohm = 4.0;           // the IRED as a resistor; <= 0: open circuit
  std::vector<std::string> errors;  // the error queue
  std::vector<std::string> commands;
  int drop_next = 0;
  int wrong_readings = 0;  // :READ? answers with a damaged current digit
  int flipped_output = 0;  // :OUTP? answers with its one bit flipped ("1" -> "0")

  double Volts() const {
    if (load_ohm <= 0) return compliance_v;
    return std::min(level_a * load_ohm, compliance_v);
  }
  bool Compliance() const { return output && (load_ohm <= 0 || level_a * load_ohm > compliance_v); }

  std::vector<std::string> Respond(const std::string& line) {
    commands.push_back(line);
    std::string reply;
    if (line == "*IDN?") {
      reply = idn;
    } else if (line == "*CLS") {
      errors.clear();
    } else if (line == "*RST") {
      function = "VOLT";
      level_a = 0;
      output = false;
    } else if (line == ":SOUR:FUNC CURR") {
      function = "CURR";
    } else if (line == ":SOUR:FUNC?") {
      reply = function;
    } else if (line.rfind(":SENS:VOLT:PROT ", 0) == 0) {
      compliance_v = std::stod(line.substr(16));
    } else if (line.rfind(":SOUR:CURR:LEV ", 0) == 0) {
      level_a = std::stod(line.substr(15));
      if (level_a > 1.05) {
        errors.push_back("-222,\"Parameter data out of range\"");
        level_a = 0;
      }
    } else if (line == ":OUTP ON") {
      output = true;
    } else if (line == ":OUTP OFF") {
      output = false;
    } else if (line == ":OUTP?") {
      reply = OutputReply();
    } else if (line == ":SOUR:CURR:LEV?") {
      reply = LevelReply();
    } else if (line == ":READ?") {
      reply = ReadReply();
    } else if (line == ":SENS:VOLT:PROT:TRIP?") {
      reply = Compliance() ? "1" : "0";
    } else if (line == ":SYST:ERR?") {
      reply = NextError();
    } else {
      errors.push_back("-113,\"Undefined header\"");
    }
    if (reply.empty()) return {};
    if (drop_next > 0) {
      --drop_next;
      return {};
    }
    return {reply};
  }
  // :OUTP?: the output's state, its bit flipped while flipped_output lasts.
  std::string OutputReply() {
    if (flipped_output > 0) {
      --flipped_output;
      return output ? "0" : "1";
    }
    return output ? "1" : "0";
  }
  // :SOUR:CURR:LEV?: the level set, in amperes.
  std::string LevelReply() const {
    char buf[40];
    std::snprintf(buf, sizeof(buf), "%+.6E", level_a);
    return buf;
  }
  // :READ?: "V,I,R,T,STAT", the current's digit damaged while wrong_readings lasts.
  std::string ReadReply() {
    double amps = Compliance() ? (load_ohm <= 0 ? 0.0 : compliance_v / load_ohm) : level_a;
    if (wrong_readings > 0) {
      --wrong_readings;
      amps += 0.1;
    }
    char buf[160];
    std::snprintf(buf, sizeof(buf), "%+.6E,%+.6E,+9.910000E+37,+1.234560E+02,%+.6E", Volts(), amps,
                  Compliance() ? 8.0 : 0.0);
    return buf;
  }
  // :SYST:ERR?: the oldest error of the queue, taken off it; 0,"No error" when it is empty.
  std::string NextError() {
    if (errors.empty()) return "0,\"No error\"";
    const std::string error = errors.front();
    errors.erase(errors.begin());
    return error;
  }
  void PowerCycle() {
    function = "VOLT";
    level_a = 0;
    output = false;
  }
};

DeviceSpec SourceSpec() {
  DeviceSpec spec = FakeDeviceSpec("source", "scpi_source", "/dev/ttyUSB2", 20);
  spec.settings["compliance_v"] = {"3.0", 24};
  return spec;
}

struct Bench : FakeDeviceBench<SourceMeter> {
  SourceMeter& meter = device;
  CurrentSource* source = driver->source();
  explicit Bench(const DeviceSpec& spec = SourceSpec()) : FakeDeviceBench("scpi_source", spec) {}
};

TEST(ScpiSource, RegistersAsSourceDriver) {
  const DriverInfo* info = FindDriver("scpi_source");
  ASSERT_NE(info, nullptr);
  EXPECT_EQ(info->roles, std::vector<std::string>{"source"});
  EXPECT_EQ(info->line_end, "\n");
}

TEST(ScpiSource, IdentifyChecksTheIdentityAndLeavesTheOutputOff) {
  Bench b;
  const DeviceIdentity id = b.source->Identify();
  EXPECT_EQ(id.vendor, "KEITHLEY INSTRUMENTS INC.");
  EXPECT_EQ(id.model, "MODEL 2400");
  EXPECT_EQ(id.serial, "1234567");
  EXPECT_EQ(b.meter.function, "CURR");
  EXPECT_DOUBLE_EQ(b.meter.compliance_v, 3.0);
  EXPECT_FALSE(b.meter.output);
  EXPECT_EQ(b.meter.commands.at(1), "*CLS");
  EXPECT_EQ(b.meter.commands.at(2), "*RST");
}

TEST(ScpiSource, WrongInstrumentIsADeviceErrorBeforeAnyOutput) {
  Bench b;
  b.meter.idn = "Agilent Technologies,34401A,0,11-5-2";
  EXPECT_THROW(b.source->Identify(), DeviceError);
  for (const std::string& c : b.meter.commands) EXPECT_EQ(c.find(":OUTP ON"), std::string::npos);
  EXPECT_EQ(b.meter.commands.size(), 1u);  // nothing but *IDN?

  Bench silent;
  silent.wire->respond = nullptr;
  EXPECT_THROW(silent.source->Identify(), DeviceError);
}

TEST(ScpiSource, SetsAndMeasuresTheCurrentInMilliamps) {
  Bench b;
  b.source->Identify();
  b.source->SetCurrent(500.0);
  EXPECT_TRUE(b.meter.output);
  EXPECT_NEAR(b.meter.level_a, 0.5, 1e-12);
  EXPECT_DOUBLE_EQ(b.source->setpoint_ma(), 500.0);
  const SourceReading r = b.source->Measure();
  EXPECT_NEAR(r.current_ma, 500.0, 1e-6);
  EXPECT_NEAR(r.voltage_v, 2.0, 1e-6);
  EXPECT_FALSE(r.in_compliance);
  EXPECT_TRUE(r.output_on);
  b.source->SetCurrent(0.0);
  EXPECT_FALSE(b.meter.output);
}

TEST(ScpiSource, OpenCircuitShowsAsComplianceAndNoCurrent) {
  Bench b;
  b.meter.load_ohm = 0;  // open IRED
  b.source->Identify();
  b.source->SetCurrent(500.0);
  const SourceReading r = b.source->Measure();
  EXPECT_TRUE(r.in_compliance);
  EXPECT_NEAR(r.current_ma, 0.0, 1e-9);
}

TEST(ScpiSource, ErrorQueueEntryIsADeviceError) {
  Bench b;
  b.source->Identify();
  try {
    b.source->SetCurrent(2000.0);  // above the 2400's 1.05 A
    FAIL() << "expected DeviceError";
  } catch (const DeviceError& e) {
    EXPECT_EQ(e.device_code(), "-222,\"Parameter data out of range\"");
    EXPECT_NE(std::string(e.what()).find("/dev/ttyUSB2"), std::string::npos);
  }
}

// An error code too large for an int (a damaged or foreign instrument) is still an error entry
// named in a DeviceError, never a std::out_of_range from the parser.
TEST(ScpiSource, AnOutOfRangeErrorCodeIsStillADeviceError) {
  Bench b;
  b.source->Identify();
  b.meter.errors.push_back("99999999999,\"Odd\"");
  try {
    b.source->SetCurrent(10.0);
    FAIL() << "expected DeviceError";
  } catch (const DeviceError& e) {
    EXPECT_EQ(e.device_code(), "99999999999,\"Odd\"");
  }
}

TEST(ScpiSource, LostQueryReplyIsRetriedAfterResync) {
  Bench b;
  b.source->Identify();
  b.source->SetCurrent(100.0);
  b.meter.drop_next = 1;  // the :OUTP? reply of Measure is lost
  const SourceReading r = b.source->Measure();
  EXPECT_NEAR(r.current_ma, 100.0, 1e-6);
}

TEST(ScpiSource, GarbledReplyIsRetriedAfterResync) {
  Bench b;
  b.source->Identify();
  b.source->SetCurrent(250.0);
  int garbled = 1;
  b.wire->respond = [&b, &garbled](const std::string& line) {
    std::vector<std::string> replies = b.meter.Respond(line);
    if (line == ":READ?" && garbled-- > 0) replies = {"+2.1#0000E+00,+2.5?0000E-01"};
    return replies;
  };
  EXPECT_NEAR(b.source->Measure().current_ma, 250.0, 1e-6);
  int resyncs = 0;
  for (const std::string& c : b.meter.commands) resyncs += c == "*IDN?";
  EXPECT_EQ(resyncs, 2);  // Identify's and the resynchronisation's
}

TEST(ScpiSource, ReadingAwayFromTheSetpointIsConfirmed) {
  Bench b;
  b.source->Identify();
  b.source->SetCurrent(400.0);
  b.meter.wrong_readings = 1;
  EXPECT_NEAR(b.source->Measure().current_ma, 400.0, 1e-6);
  b.meter.load_ohm = 10.0;  // a real mismatch: 400 mA x 10 ohm is over 3 V, compliance
  const SourceReading r = b.source->Measure();
  EXPECT_NEAR(r.current_ma, 300.0, 1e-6);
  EXPECT_TRUE(r.in_compliance);
}

TEST(ScpiSource, OffSwitchesTheOutputOffAndNeverThrows) {
  Bench b;
  b.source->Identify();
  b.source->SetCurrent(300.0);
  b.source->Off();
  EXPECT_FALSE(b.meter.output);
  EXPECT_DOUBLE_EQ(b.source->setpoint_ma(), 0.0);
  b.wire->respond = nullptr;  // a dead link
  EXPECT_NO_THROW(b.source->Off());
}

TEST(ScpiSource, OffIsRepeatedWhenTheOutputStillReadsOn) {
  int lost = 1;  // before the bench: the source's destructor still writes through the handler
  Bench b;
  b.source->Identify();
  b.source->SetCurrent(300.0);
  b.wire->respond = [&b, &lost](const std::string& line) {
    if (line == ":OUTP OFF" && lost-- > 0) return std::vector<std::string>{};  // damaged
    return b.meter.Respond(line);
  };
  b.source->Off();
  EXPECT_FALSE(b.meter.output);
}

TEST(ScpiSource, DestructionSwitchesTheOutputOff) {
  Bench b;
  b.source->Identify();
  b.source->SetCurrent(300.0);
  b.driver.reset();
  EXPECT_FALSE(b.meter.output);
}

// `irdist station current 500` then `irdist station status`: each command is a new driver on
// the same instrument. A kept output stays on when the driver goes, and the next driver takes it
// as it is (no *RST).
TEST(ScpiSource, AKeptOutputStaysOnAndIsTakenAsItIsByTheNextDriver) {
  Bench b;
  b.source->KeepOutput();
  b.source->Identify();
  b.source->SetCurrent(500.0);
  b.driver.reset();
  EXPECT_TRUE(b.meter.output);
  EXPECT_NEAR(b.meter.level_a, 0.5, 1e-12);
  b.meter.commands.clear();
  std::unique_ptr<DeviceDriver> next =
      FindDriver("scpi_source")->create(SourceSpec(), std::make_unique<FakeTransport>(b.wire));
  next->source()->KeepOutput();
  next->source()->Identify();
  EXPECT_EQ(std::count(b.meter.commands.begin(), b.meter.commands.end(), "*RST"), 0);
  EXPECT_TRUE(b.meter.output);
  EXPECT_DOUBLE_EQ(next->source()->setpoint_ma(), 500.0);
  EXPECT_NEAR(next->source()->Measure().current_ma, 500.0, 1e-6);
  next->source()->Off();  // `irdist station off`
  EXPECT_FALSE(b.meter.output);
}

// Without KeepOutput (a run) an output found on is reset at connection.
TEST(ScpiSource, ARunResetsAnOutputFoundOn) {
  Bench b;
  b.meter.function = "CURR";
  b.meter.output = true;
  b.meter.level_a = 0.5;
  b.source->Identify();
  EXPECT_FALSE(b.meter.output);
  EXPECT_EQ(std::count(b.meter.commands.begin(), b.meter.commands.end(), "*RST"), 1);
}

// One flipped bit in the reply to :OUTP? ("1" -> "0") while sourcing 475 mA: the second reading
// says on, the run goes on. Off twice is a trip.
TEST(ScpiSource, AnOutputReadOffOnceIsConfirmedBeforeStopping) {
  Bench b;
  b.source->Identify();
  b.source->SetCurrent(475.0);
  b.meter.flipped_output = 1;
  EXPECT_NEAR(b.source->Measure().current_ma, 475.0, 1e-6);
  b.meter.flipped_output = 1;
  EXPECT_NO_THROW(b.source->CheckAlive());
  b.meter.output = false;
  EXPECT_THROW(b.source->CheckAlive(), DeviceError);
}

TEST(ScpiSource, PowerCycleIsARestartAndTripIsADeviceError) {
  Bench b;
  b.source->Identify();
  b.source->SetCurrent(300.0);
  b.source->CheckAlive();
  b.meter.PowerCycle();
  EXPECT_THROW(b.source->CheckAlive(), DeviceRestarted);
  b.source->SetCurrent(300.0);  // the settings are applied again
  EXPECT_EQ(b.meter.function, "CURR");
  EXPECT_TRUE(b.meter.output);
  b.meter.output = false;  // tripped: settings kept
  EXPECT_THROW(b.source->CheckAlive(), DeviceError);
}

TEST(ScpiSource, ValidateRequiresComplianceAndKnownKeys) {
  const DriverInfo* info = FindDriver("scpi_source");
  EXPECT_NO_THROW(info->validate(SourceSpec()));
  DeviceSpec none = SourceSpec();
  none.settings.clear();
  EXPECT_THROW(info->validate(none), InputError);
  DeviceSpec unknown = SourceSpec();
  unknown.settings["compliance"] = {"3", 25};
  EXPECT_THROW(info->validate(unknown), InputError);
  DeviceSpec high = SourceSpec();
  high.settings["compliance_v"] = {"500", 24};
  EXPECT_THROW(info->validate(high), InputError);
}

// Against the SourceMeter emulator (sim/scpi_emulator.cc): one flipped bit in the reply to
// :OUTP? ("1" -> "0") while sourcing 475 mA does not stop the sweep.
// The 2400 behind a serial line in virtual time: commands are taken in the order written, each
// taking effect 1 ms after it was written or after the instrument's previous reply left (it sends
// one reply at a time, and takes nothing while sending); a reply leaves `delay_ms(line, n)`
// after its command took effect (n counts that line's occurrences). A read waits for the next
// reply up to its timeout, the clock advancing by what it waited.
class LateRepliesLine : public Transport {
 public:
  LateRepliesLine(SourceMeter* meter, std::function<double(const std::string&, int)> delay_ms)
      : meter_(meter), delay_ms_(std::move(delay_ms)) {}
  void WriteLine(std::string_view line) override { inbox_.push_back({std::string(line), now_ms_}); }
  std::string ReadLine(std::chrono::milliseconds timeout) override {
    const double until_ms = now_ms_ + static_cast<double>(timeout.count());
    TakeCommandsUntil(until_ms);
    if (outbox_.empty() || outbox_.front().first > until_ms) {
      now_ms_ = until_ms;
      throw LinkError("no reply", "virtual line", "test");
    }
    now_ms_ = std::max(now_ms_, outbox_.front().first);
    std::string line = outbox_.front().second;
    outbox_.pop_front();
    return line;
  }
  void Flush() override {
    TakeCommandsUntil(now_ms_);
    while (!outbox_.empty() && outbox_.front().first <= now_ms_) outbox_.pop_front();
  }
  // The instrument as it is now: every command that took effect by the clock.
  const SourceMeter& Now() {
    TakeCommandsUntil(now_ms_);
    return *meter_;
  }

 private:
  void TakeCommandsUntil(double until_ms) {
    while (!inbox_.empty()) {
      const double effect_ms = std::max(inbox_.front().second, free_ms_) + 1.0;
      if (effect_ms > until_ms) return;
      const std::string line = inbox_.front().first;
      inbox_.pop_front();
      free_ms_ = effect_ms;
      for (std::string& reply : meter_->Respond(line)) {
        free_ms_ = effect_ms + delay_ms_(line, seen_[line]);
        outbox_.emplace_back(free_ms_, std::move(reply));
      }
      ++seen_[line];
    }
  }

  SourceMeter* meter_;
  std::function<double(const std::string&, int)> delay_ms_;
  std::deque<std::pair<std::string, double>> inbox_;   // written, not yet taken
  std::deque<std::pair<double, std::string>> outbox_;  // replies and when they arrive
  std::map<std::string, int> seen_;
  double now_ms_ = 0.0, free_ms_ = 0.0;
};

// Regression (virtual time, so the same every run): error queries whose answers come late, past
// the 100 ms reply timeout, leave a "0,No error" on its way when the next level is written; taken
// for the new level's, it let SetCurrent return while the instrument still sourced the old level.
// Every level must be the instrument's when SetCurrent returns.
TEST(ScpiSource, ALateAnswerToAnEarlierQueryNeverConfirmsALevel) {
  for (int late = 0; late < 12; ++late) {  // which error queries' answers come late
    SourceMeter meter;
    const auto delay_ms = [late](const std::string& line, int n) {
      const bool slow = line == ":SYST:ERR?" && n >= 6 + late && n % 3 != 0;
      return slow ? 150.0 : line == "*IDN?" && n % 2 == 1 ? 120.0 : 2.0;
    };
    auto owned = std::make_unique<LateRepliesLine>(&meter, delay_ms);
    LateRepliesLine* line = owned.get();
    DeviceSpec spec = SourceSpec();
    spec.reply_timeout_ms = 100;
    spec.settings["retries"] = {"8", 26};
    std::unique_ptr<DeviceDriver> driver = FindDriver("scpi_source")->create(spec, std::move(owned));
    CurrentSource* source = driver->source();
    source->Identify();
    for (const double bias_ma : {100.0, 475.0, 250.0, 600.0, 50.0, 320.0}) {
      source->SetCurrent(bias_ma);
      ASSERT_NEAR(line->Now().level_a * 1000.0, bias_ma, 1e-6)
          << "SetCurrent(" << bias_ma << ") returned before the instrument took it; late from "
          << late;
      ASSERT_TRUE(line->Now().output);
    }
  }
}

// A level the instrument keeps reading back as another (a front panel left in a menu, a level
// clamped) is a DeviceError naming what it answers, never a set-point taken on trust.
TEST(ScpiSource, ALevelThatNeverReadsBackIsADeviceError) {
  Bench b;
  b.source->Identify();
  b.wire->respond = [&b](const std::string& line) {
    std::vector<std::string> replies = b.meter.Respond(line);
    if (line == ":SOUR:CURR:LEV?") replies = {"+1.000000E-01"};
    return replies;
  };
  try {
    b.source->SetCurrent(475.0);
    FAIL() << "expected DeviceError";
  } catch (const DeviceError& e) {
    EXPECT_NE(std::string(e.what()).find("+1.000000E-01"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(":SOUR:CURR:LEV?"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(b.meter.output) << "the output switched on at a level never confirmed";
}

TEST(ScpiSourceEmulated, OneFlippedBitInTheOutputStateDoesNotStopTheRun) {
  sim::World world(20.0);
  const std::string rig =
      "station:\n  devices:\n    source:\n      driver: scpi_source\n      port: auto\n"
      "      compliance_v: 3.0\n"
      "virtual:\n  devices:\n    source:\n      flip_reply: \":OUTP?\"\n"
      "      flip_byte: -1\n      flip_bit: 0\n";
  std::unique_ptr<sim::DeviceEmulator> emulator = sim::FindEmulator("scpi_source")->create(
      world, {"source", "scpi_source", "inline.yaml", rig, 1});
  DeviceSpec spec = SourceSpec();
  spec.port = emulator->Start();
  SerialOptions serial;
  serial.line_end = FindDriver("scpi_source")->line_end;
  std::unique_ptr<DeviceDriver> driver = FindDriver("scpi_source")->create(
      spec, std::make_unique<SerialTransport>(spec.port, serial));
  CurrentSource* source = driver->source();
  source->Identify();
  source->SetCurrent(475.0);
  EXPECT_NEAR(source->Measure().current_ma, 475.0, 0.01);
  EXPECT_NEAR(world.Pose().bias_ma, 475.0, 0.01);
}

// The driver of `spec` on the emulator's pty (started here), replies awaited 100 ms.
std::unique_ptr<DeviceDriver> OpenOnEmulator(sim::DeviceEmulator& emulator, DeviceSpec spec) {
  spec.port = emulator.Start();
  spec.reply_timeout_ms = 100;
  SerialOptions serial;
  serial.line_end = FindDriver("scpi_source")->line_end;
  return FindDriver("scpi_source")->create(
      spec, std::make_unique<SerialTransport>(spec.port, serial));
}

// Regression: with replies dropped and delayed past the reply timeout, SetCurrent returns
// only once the instrument has taken the level (its error query answered after it, in order; a
// late answer to an earlier query is never that answer), so no frame is exposed at the old one.
TEST(ScpiSourceEmulated, NoLevelCountsAsSetBeforeTheInstrumentTookIt) {
  sim::World world(20.0);
  const std::string rig =
      "station:\n  devices:\n    source:\n      driver: scpi_source\n      port: auto\n"
      "      compliance_v: 3.0\n";
  std::unique_ptr<sim::DeviceEmulator> emulator = sim::FindEmulator("scpi_source")->create(
      world, {"source", "scpi_source", "inline.yaml", rig, 1});
  DeviceSpec spec = SourceSpec();
  spec.settings["retries"] = {"8", 26};
  std::unique_ptr<DeviceDriver> driver = OpenOnEmulator(*emulator, spec);
  CurrentSource* source = driver->source();
  source->Identify();
  emulator->SetFaults(testing::LossyReplies(4.0));  // 0.2 s at this time scale: late replies
  for (const double bias_ma : {100.0, 475.0, 250.0, 600.0, 50.0, 320.0}) {
    source->SetCurrent(bias_ma);
    EXPECT_NEAR(world.Pose().bias_ma, bias_ma, 0.01) << "returned before the level was taken";
  }
}

// A SourceMeter emulator whose power cycle boots for 6 simulated s (3 s at this time scale),
// its driver giving up on a silent query after 4 x 100 ms and waiting up to 20 s for a boot.
struct BootingMeter {
  BootingMeter()
      : emulator(sim::FindEmulator("scpi_source")->create(
            world, {"source", "scpi_source", "inline.yaml",
                    "station:\n  devices:\n    source:\n      driver: scpi_source\n"
                    "      port: auto\n      compliance_v: 3.0\n"
                    "virtual:\n  devices:\n    source:\n      reset_s: 6\n",
                    1})) {
    DeviceSpec spec = SourceSpec();
    spec.settings["reset_wait_s"] = {"20", 27};
    driver = OpenOnEmulator(*emulator, spec);
  }
  // Identified, sourcing `bias_ma`, then its power cut (the boot begins).
  CurrentSource& CutPowerWhileAt(double bias_ma) {
    CurrentSource& source = *driver->source();
    source.Identify();
    source.SetCurrent(bias_ma);
    emulator->PowerCycle();
    return source;
  }
  double WorldBiasMa() const { return world.Pose().bias_ma; }
  sim::World world{2.0};
  std::unique_ptr<sim::DeviceEmulator> emulator;
  std::unique_ptr<DeviceDriver> driver;
};

// Regression: a SourceMeter that loses power while sourcing boots silently (6 simulated s,
// 3 s here; the driver gives up on a query after 4 x 100 ms): the next check waits it out up to
// reset_wait_s, sees the same *IDN? again and reports a restart, never a dead link; the level set
// again lands, with the source settings the power cut erased.
TEST(ScpiSourceEmulated, ASilentPowerCutIsWaitedOutAndTheLevelSetAgain) {
  BootingMeter meter;
  CurrentSource& source = meter.CutPowerWhileAt(475.0);
  EXPECT_NEAR(meter.WorldBiasMa(), 0.0, 0.01);  // the IRED dark while the instrument boots
  EXPECT_THROW(source.Measure(), DeviceRestarted);
  source.SetCurrent(475.0);
  EXPECT_NEAR(source.Measure().current_ma, 475.0, 0.01);
  EXPECT_NEAR(meter.WorldBiasMa(), 475.0, 0.01);
}

// A level set while the instrument boots is lost with it: the error query after it, answered
// only once the boot is over, is no confirmation of the level (a restart instead).
TEST(ScpiSourceEmulated, ALevelSentDuringTheBootIsNeverTakenAsSet) {
  BootingMeter meter;
  CurrentSource& source = meter.CutPowerWhileAt(100.0);
  EXPECT_THROW(source.SetCurrent(475.0), DeviceRestarted);
  EXPECT_NEAR(meter.WorldBiasMa(), 0.0, 0.01);
  source.SetCurrent(475.0);
  EXPECT_NEAR(meter.WorldBiasMa(), 475.0, 0.01);
}

}  // namespace
}  // namespace irdist
