#include "station/station.h"

#include <gtest/gtest.h>

#include "base/input_error.h"
#include "tests/station/rig_fixture.h"

namespace irdist {
namespace {

using testing::VirtualStationRig;

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

}  // namespace
}  // namespace irdist
