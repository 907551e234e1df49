#include "station/station.h"

#include <gtest/gtest.h>

#include <fstream>

#include "base/input_error.h"
#include "tests/station/rig_fixture.h"

namespace irdist {
namespace {

using testing::VirtualStationRig;

// The options refuse each bad field by name: a port override without a device name or a path, a
// move timeout of 0.
TEST(StationOptions, RefusesEachBadFieldByName) {
  std::string why;
  EXPECT_TRUE(StationOptions().IsValid(&why)) << why;
  StationOptions o;
  o.ports["slide"] = "";
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("ports"), std::string::npos) << why;
  o = StationOptions();
  o.move_timeout = std::chrono::milliseconds(0);
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("move_timeout"), std::string::npos) << why;
}

TEST(Station, IdentifiesEveryDeviceBeforeAnythingMoves) {
  VirtualStationRig rig(100.0);
  const std::vector<DeviceIdentity>& ids = rig.station->Identify();
  ASSERT_EQ(ids.size(), 1u);
  EXPECT_EQ(ids[0].kind, "irdist_station");
  EXPECT_EQ(ids[0].vendor, "IRDIST");
  EXPECT_EQ(ids[0].port, rig.port);
  EXPECT_NE(rig.station->IdentityBrief().find("station: irdist_station on "), std::string::npos);
  EXPECT_EQ(rig.emulator.Reboots(), 0u);
  EXPECT_FALSE(rig.world.Pose().moving);
}

TEST(Station, AnUnknownDriverIsAnInputErrorNamingTheEntry) {
  StationSpec spec = VirtualStationRig::Spec("/dev/null", 5.0);
  spec.devices[0].driver = "no_such_driver";
  spec.devices[0].file = "rig.yaml";
  spec.devices[0].line = 12;
  try {
    Station station(spec, {});
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.Line(), 12);
    EXPECT_NE(e.Message().find("irdist_station"), std::string::npos) << e.what();
  }
}

TEST(Station, AnAutoPortWithoutOverrideIsRefused) {
  StationSpec spec = VirtualStationRig::Spec("auto", 5.0);
  EXPECT_THROW(Station(spec, {}), InputError);
}

TEST(Station, MovesAllMotionDevicesAndReadsThePosition) {
  VirtualStationRig rig(100.0);
  rig.station->Identify();
  rig.station->Home();
  rig.station->MoveTo({1800.0, 5.0, -3.0});
  const StationPosition p = rig.station->Position();
  EXPECT_NEAR(p.slide_mm, 1800.0, 0.011);
  EXPECT_NEAR(p.pan_deg, 5.0, 0.011);
  EXPECT_NEAR(p.tilt_deg, -3.0, 0.011);
  EXPECT_NEAR(rig.world.Pose().slide_mm, 1800.0, 1e-6);
}

// A track's speed (Motion::SetSpeed through the protocol's SPEED): the next move cruises at it,
// Speeds() reports it; beyond the station's fastest (max_speed) it is refused.
TEST(Station, SetsAnAxisCruiseSpeedForTheNextMove) {
  sim::EmulatorOptions options;
  options.slide.max_speed = 600.0;
  VirtualStationRig rig(10.0, options);
  rig.station->Identify();
  rig.station->Home();
  EXPECT_DOUBLE_EQ(rig.station->Speeds().at(Axis::kSlide).speed, 200.0);
  EXPECT_THROW(rig.station->SetSpeed(Axis::kSlide, 700.0), Error);
  const double t0_s = rig.world.clock().Now();
  rig.station->SetSpeed(Axis::kSlide, 500.0);
  EXPECT_DOUBLE_EQ(rig.station->Speeds().at(Axis::kSlide).speed, 500.0);
  rig.station->MoveTo({2500.0, 0.0, 0.0});  // 1000 -> 2500 mm: cruising 1.25-3.0 s in
  const sim::TrajectoryPoint cruise = rig.world.TruthAt(t0_s + 2.0);
  ASSERT_TRUE(cruise.known);
  EXPECT_NEAR(cruise.slide_mm_s, 500.0, 1e-6);
}

// A move given up (a track's Ctrl-C): the station stops where it is, short of the target.
TEST(Station, AMoveGivenUpStopsTheStationShortOfItsTarget) {
  VirtualStationRig rig(10.0);
  rig.station->Identify();
  rig.station->Home();
  EXPECT_TRUE(rig.station->MoveToUnless({1200.0, 0.0, 0.0}, [] { return false; }));
  EXPECT_NEAR(rig.station->Position().slide_mm, 1200.0, 0.011);
  int polls = 0;  // gives up after a few polls of the moving axes (1200 -> 3000 mm takes 9.5 s)
  EXPECT_FALSE(rig.station->MoveToUnless({3000.0, 0.0, 0.0}, [&polls] { return ++polls > 3; }));
  const double stopped_mm = rig.station->Position().slide_mm;
  EXPECT_GT(stopped_mm, 1200.0);
  EXPECT_LT(stopped_mm, 2500.0);
  EXPECT_EQ(rig.station->States().front().second, MotionState::kIdle);
}

TEST(Station, AnEStopAtStartGetsAClearMessageAtOnce) {
  VirtualStationRig rig(100.0);
  rig.station->Identify();
  rig.emulator.PressEmergencyStop();
  try {
    rig.station->CheckReadyToStart();
    ADD_FAILURE() << "no error";
  } catch (const StationNotReadyError& e) {
    EXPECT_NE(std::string(e.what()).find("emergency stop"), std::string::npos) << e.what();
  }
  EXPECT_THROW(rig.station->CheckAlive(), DeviceError);
}

TEST(Station, AnOpenIredStopsWithTheMessage) {
  sim::EmulatorOptions options;
  options.open_circuit = true;
  VirtualStationRig rig(100.0, options);
  rig.station->Identify();
  rig.station->SetCurrent(500.0);
  try {
    rig.station->CheckCurrent(rig.station->MeasureCurrent());
    ADD_FAILURE() << "no error";
  } catch (const CurrentMismatchError& e) {
    EXPECT_NE(std::string(e.what()).find("open"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("500.00 mA is set"), std::string::npos) << e.what();
  }
}

// A device that restarted lost its current: that is a restart (retake), not an open IRED.
TEST(Station, ACurrentLostToARestartIsARestart) {
  VirtualStationRig rig(100.0);
  rig.station->Identify();
  rig.station->Home();
  rig.station->SetCurrent(500.0);
  rig.emulator.Reboot();
  EXPECT_THROW(rig.station->MeasureCheckedCurrent(), DeviceRestarted);
}

TEST(Station, AGoodIredPassesTheCurrentCheck) {
  VirtualStationRig rig(100.0);
  rig.station->Identify();
  rig.station->SetCurrent(500.0);
  EXPECT_NO_THROW(rig.station->CheckCurrent(rig.station->MeasureCurrent()));
}

TEST(Station, SwitchesTheIredOffWhenDestroyed) {
  VirtualStationRig rig(100.0);
  rig.station->Identify();
  rig.station->SetCurrent(300.0);
  EXPECT_DOUBLE_EQ(rig.world.Pose().bias_ma, 300.0);
  rig.station.reset();
  EXPECT_DOUBLE_EQ(rig.world.Pose().bias_ma, 0.0);
}

TEST(Station, ReportsTheSpeedOfEveryAxis) {
  VirtualStationRig rig(100.0);
  const std::map<Axis, AxisSpeed> speeds = rig.station->Speeds();
  ASSERT_EQ(speeds.size(), 3u);
  EXPECT_GT(speeds.at(Axis::kSlide).speed, 0.0);
  EXPECT_GT(speeds.at(Axis::kPan).speed, 0.0);
}

// Two boxes composed: one moves, the other sources the current; one log, lines prefixed by the
// device's name.
TEST(Station, ComposesRolesAcrossDevicesWithOneLog) {
  sim::World world_a(100.0), world_b(100.0);
  sim::StationEmulator emulator_a(world_a, {}), emulator_b(world_b, {});
  StationSpec spec = VirtualStationRig::Spec(emulator_a.Start(), 5.0);
  DeviceSpec b = spec.devices[0];
  spec.devices[0].name = "a";
  b.name = "b";
  b.port = emulator_b.Start();
  spec.devices.push_back(b);
  spec.motion = {"a"};
  spec.source = "b";
  spec.trigger = "a";
  const std::string log_path = std::string(IRDIST_BINARY_DIR) + "/station_test_composed.log";
  {
    LineLog log(log_path);
    StationOptions options;
    options.log = &log;
    Station station(spec, options);
    EXPECT_EQ(station.Identify().size(), 2u);
    station.Home();
    station.SetCurrent(250.0);
    station.MoveTo({1700.0, 0.0, 0.0});
    EXPECT_NEAR(world_a.Pose().slide_mm, 1700.0, 1e-6);
    EXPECT_DOUBLE_EQ(world_a.Pose().bias_ma, 0.0);
    EXPECT_DOUBLE_EQ(world_b.Pose().bias_ma, 250.0);
  }
  EXPECT_DOUBLE_EQ(world_b.Pose().bias_ma, 0.0);  // off when the station closed
  std::ifstream in(log_path);
  std::string line;
  int a_lines = 0, b_lines = 0;
  while (std::getline(in, line)) {
    a_lines += line.find(" a: ") != std::string::npos ? 1 : 0;
    b_lines += line.find(" b: ") != std::string::npos ? 1 : 0;
  }
  EXPECT_GT(a_lines, 0);
  EXPECT_GT(b_lines, 0);
}

TEST(Station, AnAxisDrivenTwiceIsRefusedBeforeAnythingMoves) {
  sim::World world_a(100.0), world_b(100.0);
  sim::StationEmulator emulator_a(world_a, {}), emulator_b(world_b, {});
  StationSpec spec = VirtualStationRig::Spec(emulator_a.Start(), 5.0);
  DeviceSpec b = spec.devices[0];
  spec.devices[0].name = "a";
  b.name = "b";
  b.port = emulator_b.Start();
  spec.devices.push_back(b);
  spec.motion = {"a", "b"};
  spec.source = "a";
  spec.trigger = "a";
  for (DeviceSpec& d : spec.devices) d.file = "two.yaml";
  try {
    Station station(spec, {});  // refused before any port is opened
    ADD_FAILURE() << "two devices on one axis accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.File(), "two.yaml");
    EXPECT_NE(e.Message().find("axis slide is driven by 2 motion devices (a, b)"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(world_a.Pose().slide_mm, world_b.Pose().slide_mm);  // nothing moved
}

// A role given to a device whose driver cannot fill it names the rig file's line and the devices
// that can, before any port is opened (was an internal check, station.cc:69/73).
TEST(Station, ARoleADeviceCannotFillNamesTheRigFileLine) {
  StationSpec spec;
  spec.devices = {VirtualStationRig::Spec("/nonexistent/pty", 5.0).devices[0]};
  spec.devices[0].name = "box";
  spec.devices[0].file = "rig.yaml";
  spec.devices[0].line = 12;
  DeviceSpec source;
  source.name = "meter";
  source.driver = "scpi_source";
  source.port = "/nonexistent/pty2";
  source.file = "rig.yaml";
  source.line = 20;
  spec.devices.push_back(source);
  spec.motion = {"meter"};  // a source meter cannot move
  spec.source = "meter";
  spec.trigger = "box";
  try {
    Station station(spec, {});
    ADD_FAILURE() << "a source meter accepted as a motion device";
  } catch (const InputError& e) {
    EXPECT_EQ(e.File(), "rig.yaml");
    EXPECT_EQ(e.Line(), 20);
    EXPECT_NE(e.Message().find("cannot fill the motion role; name one that can: box"),
              std::string::npos)
        << e.what();
  }
  spec.motion = {"box"};
  spec.trigger = "meter";  // nor trigger the camera
  try {
    CheckStationRoles(spec);
    ADD_FAILURE() << "a source meter accepted as the trigger";
  } catch (const InputError& e) {
    EXPECT_EQ(e.Line(), 20);
    EXPECT_NE(e.Message().find("station.roles.trigger names device 'meter'"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace irdist
