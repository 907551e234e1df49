// Each station driver against its emulator over a real pty, composed as the rig file
// recipes/rigs/virtual-lab.yaml composes them (Zaber slide, FLIR PTU head, SCPI source; no
// camera: the trigger role is not used here). The emulators are written from the vendors'
// documentation and share no code with the drivers; where the two meet, this is the test.
// Every fault knob of sim/device_emulator.h and sim/scpi_emulator.h either completes with the
// positions landing in the World, or stops with a typed irdist::Error naming the device.
// Each test prints one "FAULT <device> <fault> -> <outcome>" line (docs/devices/README.md).

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <memory>
#include <string>
#include <thread>

#include "app/inputs/rig.h"
#include "base/check.h"
#include "sim/device_emulator.h"
#include "sim/scpi_emulator.h"
#include "sim/world.h"
#include "station/line_log.h"
#include "station/station.h"
#include "station/transport.h"
#include "tests/integration/run_helpers.h"

namespace irdist {
namespace {

std::string LabRigPath() {
  return std::string(IRDIST_SOURCE_DIR) + "/recipes/rigs/virtual-lab.yaml";
}

// The three emulators of virtual-lab on a fast World, and a Station over their ptys.
class LabDevices : public ::testing::Test {
 protected:
  static constexpr double kTimeScale = 20.0;
  void SetUp() override {
    rig_ = LoadRig(LabRigPath());
    const std::string text = testing::ReadAll(LabRigPath());
    for (const DeviceSpec& d : rig_.station.composition.devices) {
      const sim::EmulatorInfo* info = sim::FindEmulator(d.driver);
      ASSERT_NE(info, nullptr) << d.driver;
      emulators_[d.name] = info->create(world_, {d.name, d.driver, LabRigPath(), text, 3});
      ports_[d.name] = emulators_[d.name]->Start();
    }
    const std::string name = ::testing::UnitTest::GetInstance()->current_test_info()->name();
    log_ = std::make_unique<LineLog>(std::string(IRDIST_BINARY_DIR) + "/devices_test_" + name +
                                     ".log");
  }
  void TearDown() override {
    station_.reset();
    for (auto& [name, emulator] : emulators_) emulator->Stop();
  }
  // Opens and identifies the station (a fresh one after a fault test's stop).
  Station& Open(std::chrono::milliseconds move_timeout = std::chrono::milliseconds(60000)) {
    station_.reset();
    StationOptions options;
    options.ports = ports_;
    options.log = log_.get();
    options.move_timeout = move_timeout;
    station_ = std::make_unique<Station>(rig_.station.composition, options);
    station_->Identify();
    return *station_;
  }
  void ExpectWorldAt(const StationPosition& p) {
    const sim::PoseState pose = world_.Pose();
    EXPECT_NEAR(pose.slide_mm, p.slide_mm, 0.01);             // 0.1 um microstep
    EXPECT_NEAR(pose.pan_deg, p.pan_deg, 0.026);               // 92.57 arcsec a position
    EXPECT_NEAR(pose.tilt_deg, p.tilt_deg, 0.013);             // 46.29 arcsec a position
  }
  // A short sweep: home, three poses with the IRED set and measured at each. Returns "completed"
  // with every pose landing in the World, or throws what the station threw.
  void Sweep(Station& station) {
    station.Home();
    for (const StationPosition p : {StationPosition{1500.0, 10.0, 0.0},
                                    StationPosition{2250.5, -20.0, 5.0},
                                    StationPosition{3000.0, 30.0, -5.0}}) {
      station.MoveTo(p);
      ExpectWorldAt(p);
      station.SetCurrent(500.0);
      station.CheckCurrent(station.MeasureCurrent());
      station.CheckAlive();
    }
  }
  // Runs the sweep under a fault: it must complete, or stop with a typed irdist::Error (never
  // anything else, never a hang). Prints the matrix line and returns the outcome.
  std::string SweepUnderFault(const std::string& device, const std::string& fault) {
    std::string outcome;
    try {
      Sweep(Open(std::chrono::milliseconds(8000)));
      outcome = "completed";
    } catch (const DeviceRestarted& e) {
      outcome = std::string("stopped: DeviceRestarted: ") + e.what();
    } catch (const DeviceError& e) {
      outcome = std::string("stopped: DeviceError: ") + e.what();
    } catch (const LinkError& e) {
      outcome = std::string("stopped: LinkError: ") + e.what();
    } catch (const Error& e) {
      outcome = std::string("stopped: ") + e.what();
    }
    std::cout << "FAULT " << device << " " << fault << " -> " << outcome << "\n";
    return outcome;
  }
  void SetFaults(const std::string& device, const sim::EmulatorFaults& faults) {
    emulators_.at(device)->SetFaults(faults);
  }
  // SweepUnderFault with `faults` set on `device` (`label` names them), cleared afterwards.
  std::string SweepWithFaults(const std::string& device, const sim::EmulatorFaults& faults,
                              const std::string& label) {
    SetFaults(device, faults);
    const std::string outcome = SweepUnderFault(device, label);
    SetFaults(device, {});
    return outcome;
  }
  // Polls the World's IRED current for up to 10 host seconds.
  bool WorldCurrentReaches(double bias_ma) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (std::chrono::steady_clock::now() < until) {
      if (std::abs(world_.Pose().bias_ma - bias_ma) < 1e-9) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    return false;
  }
  std::string SourceOutcomeUnder(const sim::SourceFaults& faults, const std::string& label);
  static bool Completed(const std::string& outcome) { return outcome == "completed"; }
  static bool Names(const std::string& outcome, const std::string& text) {
    return outcome.find(text) != std::string::npos;
  }

  sim::World world_{kTimeScale};
  Rig rig_;
  std::map<std::string, std::unique_ptr<sim::DeviceEmulator>> emulators_;
  std::map<std::string, std::string> ports_;
  std::unique_ptr<LineLog> log_;
  std::unique_ptr<Station> station_;
};

TEST_F(LabDevices, IdentifiesEachDeviceAsItsKind) {
  Station& station = Open();
  const std::vector<DeviceIdentity>& ids = station.Identify();
  ASSERT_EQ(ids.size(), 3u);
  std::map<std::string, DeviceIdentity> by_kind;
  for (const DeviceIdentity& id : ids) by_kind[id.kind] = id;
  ASSERT_EQ(by_kind.count("zaber_ascii"), 1u);
  ASSERT_EQ(by_kind.count("flir_ptu"), 1u);
  ASSERT_EQ(by_kind.count("scpi_source"), 1u);
  EXPECT_EQ(by_kind["zaber_ascii"].port, ports_["slide"]);
  EXPECT_NE(by_kind["scpi_source"].model.find("2400"), std::string::npos)
      << by_kind["scpi_source"].Brief();
  EXPECT_NE(by_kind["scpi_source"].serial.find("4312345"), std::string::npos);
  EXPECT_FALSE(world_.Pose().moving);
}

TEST_F(LabDevices, AWrongDeviceOnAPortIsADeviceErrorBeforeAnythingMoves) {
  std::swap(ports_["slide"], ports_["head"]);
  const double slide_mm = world_.Pose().slide_mm;
  EXPECT_THROW(Open(), Error);
  EXPECT_DOUBLE_EQ(world_.Pose().slide_mm, slide_mm);
}

TEST_F(LabDevices, HomesAndMovesLandInTheWorldWithinOneStep) {
  Station& station = Open();
  station.Home();
  EXPECT_TRUE(station.homed());
  const StationPosition home = station.Position();
  EXPECT_NEAR(world_.Pose().slide_mm, home.slide_mm, 0.01);
  for (const StationPosition p : {StationPosition{1234.567, 12.3, -4.5},
                                  StationPosition{3499.0, -44.0, 44.0},
                                  StationPosition{1000.5, 0.0, 0.0}}) {
    station.MoveTo(p);
    ExpectWorldAt(p);
    const StationPosition read = station.Position();
    EXPECT_NEAR(read.slide_mm, p.slide_mm, 0.01);
    EXPECT_NEAR(read.pan_deg, p.pan_deg, 0.026);
    EXPECT_NEAR(read.tilt_deg, p.tilt_deg, 0.013);
  }
}

TEST_F(LabDevices, MovesBeyondTheDevicesTravelAreRefusedWithTheDeviceNamed) {
  Station& station = Open();
  station.Home();
  try {
    station.MoveTo({3600.0, 0.0, 0.0});  // the stage's travel ends at 3500 mm
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("zaber_ascii"), std::string::npos) << e.what();
  }
  try {
    Open().Home();
    station_->MoveTo({2000.0, 170.0, 0.0});  // the PTU's pan ends at +-154 deg
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("flir_ptu"), std::string::npos) << e.what();
  }
}

TEST_F(LabDevices, SourceSetsAndMeasuresTheCurrentInMilliamps) {
  Station& station = Open();
  station.SetCurrent(500.0);
  const SourceReading reading = station.MeasureCurrent();
  EXPECT_NEAR(reading.current_ma, 500.0, 1.0);
  EXPECT_TRUE(reading.output_on);
  EXPECT_FALSE(reading.in_compliance);
  EXPECT_NEAR(world_.Pose().bias_ma, 500.0, 1.0);
  station.Off();  // written without a reply: the emulator applies it when it reads the line
  EXPECT_TRUE(WorldCurrentReaches(0.0)) << world_.Pose().bias_ma;
}

// --- reply faults, every device ---

TEST_F(LabDevices, GarbledRepliesCompleteOrStopTyped) {
  sim::EmulatorFaults faults;
  faults.garble_rate = 0.01;
  for (const std::string device : {"slide", "head", "source"}) {
    const std::string outcome = SweepWithFaults(device, faults, "garble_rate=0.01");
    EXPECT_TRUE(Completed(outcome) || Names(outcome, device == "slide"  ? "zaber"
                                                     : device == "head" ? "flir_ptu"
                                                                        : "scpi"))
        << outcome;
  }
}

TEST_F(LabDevices, DroppedRepliesAreRetriedOrStopTyped) {
  sim::EmulatorFaults faults;
  faults.drop_rate = 0.1;
  for (const std::string device : {"slide", "head", "source"}) {
    const std::string outcome = SweepWithFaults(device, faults, "drop_rate=0.1");
    EXPECT_TRUE(Completed(outcome) || Names(outcome, "stopped: ")) << outcome;
  }
}

TEST_F(LabDevices, DelayedRepliesComplete) {
  sim::EmulatorFaults faults;
  faults.delay_rate = 0.2;
  faults.delay_s = 0.5;  // simulated: 25 ms at the test's time scale
  for (const std::string device : {"slide", "head", "source"}) {
    const std::string outcome = SweepWithFaults(device, faults, "delay_rate=0.2 delay_s=0.5");
    EXPECT_TRUE(Completed(outcome)) << outcome;
  }
}

// --- power cycle in the middle of the sweep's first move, and a stuck axis ---

TEST_F(LabDevices, APowerCycleMidMoveIsNoticedNeverSilent) {
  sim::EmulatorFaults faults;
  faults.power_cycle_after_s = 0.2;
  for (const std::string device : {"slide", "head"}) {
    const std::string outcome = SweepWithFaults(device, faults, "power_cycle_after_s=0.2");
    // Either the driver re-homed and the poses still landed (checked inside Sweep), or the
    // station stopped saying the device restarted / lost its reference.
    EXPECT_TRUE(Completed(outcome) || Names(outcome, "stopped: ")) << outcome;
  }
}

TEST_F(LabDevices, APowerCycleOfTheSourceBetweenPosesStopsTyped) {
  Station& station = Open();
  station.Home();
  station.SetCurrent(500.0);
  emulators_.at("source")->PowerCycle();  // output off, settings reset
  std::string outcome = "completed";
  try {
    station.CheckAlive();
    station.CheckCurrent(station.MeasureCurrent());
  } catch (const Error& e) {
    outcome = std::string("stopped: ") + e.what();
  }
  std::cout << "FAULT source power_cycle -> " << outcome << "\n";
  EXPECT_TRUE(Names(outcome, "stopped: ")) << outcome;
}

TEST_F(LabDevices, AStuckAxisStopsWithTheAxisDeviceNamed) {
  for (const auto& [device, axis] : {std::pair<std::string, std::string>{"slide", "slide"},
                                     std::pair<std::string, std::string>{"head", "pan"}}) {
    sim::EmulatorFaults faults;
    faults.stuck_axis = axis;
    const std::string outcome = SweepWithFaults(device, faults, "stuck_axis=" + axis);
    EXPECT_TRUE(Names(outcome, "stopped: ")) << outcome;
    EXPECT_TRUE(Names(outcome, device == "slide" ? "zaber" : "flir_ptu")) << outcome;
  }
}

// --- the source's own faults ---

std::string SourceFaultOutcome(Station& station) {
  try {
    station.SetCurrent(500.0);
    station.CheckCurrent(station.MeasureCurrent());
    station.CheckAlive();
    return "completed";
  } catch (const CurrentMismatchError& e) {
    return std::string("stopped: CurrentMismatchError: ") + e.what();
  } catch (const Error& e) {
    return std::string("stopped: ") + e.what();
  }
}

// The source's outcome with `faults` set on its emulator (`label` names them in the matrix line).
std::string LabDevices::SourceOutcomeUnder(const sim::SourceFaults& faults,
                                           const std::string& label) {
  sim::SetSourceFaults(*emulators_.at("source"), faults);
  const std::string outcome = SourceFaultOutcome(Open());
  std::cout << "FAULT source " << label << " -> " << outcome << "\n";
  return outcome;
}

TEST_F(LabDevices, AnOpenCircuitIredStopsNamingTheSource) {
  sim::SourceFaults faults;
  faults.open_circuit = true;
  const std::string outcome = SourceOutcomeUnder(faults, "open_circuit");
  EXPECT_TRUE(Names(outcome, "CurrentMismatchError")) << outcome;
  EXPECT_TRUE(Names(outcome, "source")) << outcome;
}

TEST_F(LabDevices, ComplianceStopsTheRun) {
  sim::SourceFaults faults;
  faults.extra_resistance_ohm = 5.0;  // 500 mA needs 4.85 V > compliance 3 V
  const std::string outcome = SourceOutcomeUnder(faults, "compliance");
  EXPECT_TRUE(Names(outcome, "CurrentMismatchError")) << outcome;
  EXPECT_TRUE(Names(outcome, "compliance")) << outcome;
}

// The output trips 1 simulated s after it is switched on (50 ms here), after SetCurrent has read
// it back on; on a host slow enough (sanitizers, load) that the read-back itself comes after the
// trip, SetCurrent is the one that stops: either way the run stops and the IRED is off.
TEST_F(LabDevices, ATrippedOutputStopsTheRun) {
  sim::SourceFaults faults;
  faults.trip_after_s = 1.0;
  sim::SetSourceFaults(*emulators_.at("source"), faults);
  Station& station = Open();
  std::string outcome = "completed";
  try {
    station.SetCurrent(500.0);
    std::this_thread::sleep_for(std::chrono::milliseconds(100));  // 2 simulated s: tripped
    station.CheckAlive();
    station.CheckCurrent(station.MeasureCurrent());
  } catch (const Error& e) {
    outcome = std::string("stopped: ") + e.what();
  }
  std::cout << "FAULT source output_tripped -> " << outcome << "\n";
  EXPECT_TRUE(Names(outcome, "stopped: ")) << outcome;
  EXPECT_TRUE(WorldCurrentReaches(0.0));  // the IRED is off
}

}  // namespace
}  // namespace irdist
