// The Keithley 2400-class SCPI source emulator spoken to in raw lines over its pty, from the
// 2400 manual's SCPI reference (no station/ code).

#include "sim/scpi_emulator.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <sstream>
#include <vector>

#include "base/input_error.h"
#include "tests/sim/pty_host.h"

namespace irdist::sim {
namespace {

using testing::PtyHost;
using testing::WaitFor;

std::string Rig(const std::string& virtual_extra = "") {
  return "station:\n"
         "  devices:\n"
         "    source:\n"
         "      driver: scpi_source\n"
         "      port: auto\n"
         "      compliance_v: 3.0\n"
         "virtual:\n"
         "  devices:\n"
         "    source:\n"
         "      forward_voltage_v: 1.5\n"
         "      series_resistance_ohm: 2.0\n" +
         virtual_extra;
}

std::vector<double> Values(const std::string& reply) {
  std::vector<double> values;
  std::istringstream in(reply);
  std::string item;
  while (std::getline(in, item, ',')) values.push_back(std::strtod(item.c_str(), nullptr));
  return values;
}

class ScpiEmulatorTest : public ::testing::Test {
 protected:
  void SetUp() override {
    emulator_ = testing::MakeEmulator(world_, "scpi_source", "source", Rig());
    ASSERT_NE(emulator_, nullptr);
    host_ = std::make_unique<PtyHost>(emulator_->Start());
  }
  std::string Ask(const std::string& line, int timeout_ms = 3000) {
    return host_->Ask(line + "\n", timeout_ms);
  }
  void Send(const std::string& line) { host_->Send(line + "\n"); }
  // The usual set-up of a current source for an IRED.
  void SourceCurrent(double amps, double compliance_v) {
    Send("*RST");
    Send(":SOUR:FUNC CURR");
    Send(":SOUR:CURR " + std::to_string(amps));
    Send(":SENS:VOLT:PROT " + std::to_string(compliance_v));
    EXPECT_EQ(Ask("*OPC?"), "1");
  }

  World world_{20.0};
  std::unique_ptr<DeviceEmulator> emulator_;
  std::unique_ptr<PtyHost> host_;
};

TEST_F(ScpiEmulatorTest, IdentifiesItselfAndStartsWithAnEmptyErrorQueue) {
  const std::string idn = Ask("*IDN?");
  EXPECT_EQ(idn.rfind("KEITHLEY INSTRUMENTS INC.,MODEL 2400,", 0), 0u) << idn;
  EXPECT_EQ(Ask(":SYST:ERR?"), "0,\"No error\"");
  EXPECT_EQ(Ask(":OUTP?"), "0");
  EXPECT_EQ(Ask(":SOUR:FUNC?"), "VOLT");  // the *RST / power-on source function
  EXPECT_EQ(Ask(":FORM:ELEM?"), "VOLT,CURR,RES,TIME,STAT");
}

TEST_F(ScpiEmulatorTest, SourcesCurrentIntoTheWorldOnlyWhileTheOutputIsOn) {
  SourceCurrent(0.5, 3.0);
  EXPECT_EQ(Ask(":source:current:level?"), "+5.000000E-01");  // long forms, any case
  EXPECT_EQ(world_.Pose().bias_ma, 0.0);
  Send(":OUTP ON");
  EXPECT_EQ(Ask(":OUTP:STAT?"), "1");
  EXPECT_NEAR(world_.Pose().bias_ma, 500.0, 1e-9);
  const std::vector<double> r = Values(Ask(":READ?"));
  ASSERT_EQ(r.size(), 5u);
  EXPECT_NEAR(r[0], 1.5 + 2.0 * 0.5, 1e-6);  // forward voltage + I R
  EXPECT_NEAR(r[1], 0.5, 1e-9);
  EXPECT_NEAR(r[2], 9.91e37, 1e32);          // resistance not measured
  EXPECT_EQ(static_cast<unsigned>(r[4]) & 8u, 0u);  // not in compliance
  Send(":FORM:ELEM CURR");
  EXPECT_EQ(Ask(":MEAS:CURR?"), "+5.000000E-01");
  Send(":OUTP OFF");
  EXPECT_EQ(Ask("*OPC?"), "1");
  EXPECT_EQ(world_.Pose().bias_ma, 0.0);
}

TEST_F(ScpiEmulatorTest, ComplianceLimitsTheCurrentPhysically) {
  SourceCurrent(0.5, 2.0);  // needs 2.5 V: only (2.0 - 1.5) / 2 = 0.25 A flows
  Send(":OUTP ON");
  const std::vector<double> r = Values(Ask(":READ?"));
  ASSERT_EQ(r.size(), 5u);
  EXPECT_NEAR(r[0], 2.0, 1e-9);
  EXPECT_NEAR(r[1], 0.25, 1e-9);
  EXPECT_NE(static_cast<unsigned>(r[4]) & 8u, 0u);  // status word bit 3: compliance
  EXPECT_EQ(Ask(":SENS:VOLT:PROT:TRIP?"), "1");
  EXPECT_NEAR(world_.Pose().bias_ma, 250.0, 1e-9);
}

TEST_F(ScpiEmulatorTest, QueuesErrorsForBadCommandsAndValues) {
  Send(":SOUR:FROB 3");
  Send(":SOUR:CURR 5");       // beyond the 1.05 A range
  Send(":SOUR:CURR abc");
  Send(":OUTP MAYBE");
  Send(":SOUR:CURR");
  EXPECT_EQ(Ask(":SYST:ERR?"), "-113,\"Undefined header\"");
  EXPECT_EQ(Ask(":SYST:ERR:NEXT?"), "-222,\"Data out of range\"");
  EXPECT_EQ(Ask(":SYST:ERR?"), "-104,\"Data type error\"");
  EXPECT_EQ(Ask(":SYST:ERR?"), "-224,\"Illegal parameter value\"");
  EXPECT_EQ(Ask(":SYST:ERR?"), "-109,\"Missing parameter\"");
  EXPECT_EQ(Ask(":SYST:ERR?"), "0,\"No error\"");
  EXPECT_EQ(Ask(":READ?", 300), "");  // output off: no reading, an error instead
  EXPECT_EQ(Ask(":SYST:ERR?"), "+803,\"Output disabled\"");
  for (int i = 0; i < 12; ++i) Send("*BOGUS");
  EXPECT_EQ(Ask("*OPC?"), "1");
  for (int i = 0; i < 9; ++i) EXPECT_EQ(Ask(":SYST:ERR?"), "-113,\"Undefined header\"");
  EXPECT_EQ(Ask(":SYST:ERR?"), "-350,\"Queue overflow\"");
  Send("*BOGUS");
  Send("*CLS");
  EXPECT_EQ(Ask(":SYST:ERR?"), "0,\"No error\"");
}

TEST_F(ScpiEmulatorTest, AcceptsTheUsualSetUpOfTheInstrument) {
  Send(":SENS:FUNC \"VOLT\";:SENS:CURR:RANG:AUTO ON;:SOUR:CURR:RANG 1;:SYST:BEEP:STAT OFF");
  Send(":SENSE:VOLTAGE:NPLCYCLES 1;:FORM:DATA ASC;:TRIG:COUN 1");
  EXPECT_EQ(Ask(":SYST:ERR:COUN?"), "0");
  EXPECT_EQ(Ask(":SYST:ERR?"), "0,\"No error\"");
  Send(":SOUR:FUNC CURR;:SOUR:CURR 0.2;:OUTP ON");
  EXPECT_NEAR(Values(Ask(":FETC?"))[1], 0.2, 1e-9);
}

TEST_F(ScpiEmulatorTest, SeveralQueriesInOneMessageAnswerInOneLine) {
  SourceCurrent(0.1, 3.0);
  EXPECT_EQ(Ask(":OUTP?;:SOUR:CURR?;*OPC?"), "0;+1.000000E-01;1");
}

// The output on at 475 mA; one flipped bit turns the reply to :OUTP? "1" into "0", once.
TEST(ScpiEmulatorFaults, OneFlippedBitInTheOutputState) {
  World world(20.0);
  auto emulator = testing::MakeEmulator(world, "scpi_source", "source",
                                        Rig("      flip_reply: \":OUTP?\"\n"
                                            "      flip_byte: -1\n"
                                            "      flip_bit: 0\n"));
  ASSERT_NE(emulator, nullptr);
  PtyHost host(emulator->Start());
  host.Send(":SOUR:FUNC CURR;:SOUR:CURR 0.475;:SENS:VOLT:PROT 3;:OUTP ON\n");
  EXPECT_EQ(host.Ask(":OUTP?\n"), "0");  // damaged on the wire
  EXPECT_EQ(host.Ask(":OUTP?\n"), "1");
  EXPECT_NEAR(world.Pose().bias_ma, 475.0, 1e-9);
}

TEST_F(ScpiEmulatorTest, OpenCircuitReadsZeroCurrentAtCompliance) {
  SourceCurrent(0.5, 3.0);
  SetSourceFaults(*emulator_, SourceFaults{true, 0.0, -1.0});
  Send(":OUTP ON");
  const std::vector<double> r = Values(Ask(":READ?"));
  ASSERT_EQ(r.size(), 5u);
  EXPECT_NEAR(r[0], 3.0, 1e-9);
  EXPECT_EQ(r[1], 0.0);
  EXPECT_NE(static_cast<unsigned>(r[4]) & 8u, 0u);
  EXPECT_EQ(world_.Pose().bias_ma, 0.0);
}

TEST_F(ScpiEmulatorTest, ExtraResistanceReachesCompliance) {
  SourceCurrent(0.5, 3.0);
  SetSourceFaults(*emulator_, SourceFaults{false, 8.0, -1.0});  // needs 6.5 V
  Send(":OUTP ON");
  const std::vector<double> r = Values(Ask(":READ?"));
  ASSERT_EQ(r.size(), 5u);
  EXPECT_NEAR(r[1], (3.0 - 1.5) / 10.0, 1e-9);
  EXPECT_NE(static_cast<unsigned>(r[4]) & 8u, 0u);
}

TEST_F(ScpiEmulatorTest, AnOutputTripSwitchesTheIredOffAndQueuesAnError) {
  SourceCurrent(0.3, 3.0);
  SetSourceFaults(*emulator_, SourceFaults{false, 0.0, 20.0});
  EXPECT_EQ(Ask(":OUTP ON;:OUTP?"), "1");
  EXPECT_NEAR(world_.Pose().bias_ma, 300.0, 1e-9);
  EXPECT_TRUE(WaitFor([this] { return world_.Pose().bias_ma == 0.0; }));
  EXPECT_EQ(Ask(":OUTP?"), "0");
  EXPECT_EQ(Ask(":SYST:ERR?").rfind("-300,", 0), 0u);
}

TEST_F(ScpiEmulatorTest, ReplyFaultsAndPowerCycle) {
  EmulatorFaults faults;
  faults.drop_rate = 1.0;
  emulator_->SetFaults(faults);
  EXPECT_EQ(Ask("*OPC?", 300), "");
  faults = EmulatorFaults();
  faults.garble_rate = 1.0;
  emulator_->SetFaults(faults);
  EXPECT_NE(Ask("*OPC?"), "1");
  faults = EmulatorFaults();
  faults.delay_rate = 1.0;
  faults.delay_s = 4.0;
  emulator_->SetFaults(faults);
  const double start_s = world_.clock().Now();
  EXPECT_EQ(Ask("*OPC?"), "1");
  EXPECT_GE(world_.clock().Now() - start_s, 4.0);
  emulator_->SetFaults(EmulatorFaults());
  SourceCurrent(0.2, 3.0);
  Send(":OUTP ON");
  EXPECT_EQ(Ask(":OUTP?"), "1");
  emulator_->PowerCycle();
  EXPECT_EQ(world_.Pose().bias_ma, 0.0);
  EXPECT_EQ(Ask(":OUTP?"), "0");
  EXPECT_EQ(Ask(":SOUR:FUNC?"), "VOLT");
}

// reset_s: a power cycle's boot (the 2400's power-on self-test) hears and answers nothing, and
// prints nothing when it ends; then the instrument answers with its power-on state.
TEST(ScpiEmulatorBoot, APowerCycleBootsSilently) {
  World world(20.0);
  std::unique_ptr<DeviceEmulator> emulator =
      testing::MakeEmulator(world, "scpi_source", "source", Rig("      reset_s: 20\n"));
  ASSERT_NE(emulator, nullptr);
  PtyHost host(emulator->Start());
  EXPECT_EQ(host.Ask("*OPC?\n"), "1");
  emulator->PowerCycle();
  EXPECT_EQ(host.Ask("*OPC?\n", 300), "");
  EXPECT_EQ(host.ReadLine(1500), "");  // nothing at the boot's end, the lost query unanswered
  EXPECT_EQ(host.Ask(":SOUR:FUNC?\n"), "VOLT");
}

TEST(ScpiEmulatorRig, SourceFaultsComeFromTheRigFile) {
  World world(20.0);
  auto emulator = testing::MakeEmulator(world, "scpi_source", "source",
                                        Rig("      open_circuit: true\n"));
  ASSERT_NE(emulator, nullptr);
  PtyHost host(emulator->Start());
  host.Send(":SOUR:FUNC CURR;:SOUR:CURR 0.5;:SENS:VOLT:PROT 3;:OUTP ON\n");
  const std::vector<double> r = Values(host.Ask(":READ?\n"));
  ASSERT_EQ(r.size(), 5u);
  EXPECT_EQ(r[1], 0.0);
  EXPECT_NEAR(r[0], 3.0, 1e-9);
}

TEST(ScpiEmulatorRig, BadElectricalModelIsAnErrorWithTheLine) {
  World world(1.0);
  try {
    testing::MakeEmulator(world, "scpi_source", "source",
                          "virtual:\n  devices:\n    source:\n      series_resistance_ohm: -1\n");
    FAIL() << "a negative resistance was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.Line(), 4);
  }
}

}  // namespace
}  // namespace irdist::sim
