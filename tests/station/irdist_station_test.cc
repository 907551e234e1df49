#include "station/irdist_station.h"

#include <gtest/gtest.h>

#include "base/input_error.h"
#include "tests/station/rig_fixture.h"

namespace irdist {
namespace {

using testing::VirtualStationRig;

TEST(IrdistStation, IsRegisteredForEveryRole) {
  const DriverInfo* info = FindDriver("irdist_station");
  ASSERT_NE(info, nullptr);
  EXPECT_EQ(info->roles, (std::vector<std::string>{"motion", "source", "trigger"}));
  EXPECT_EQ(info->line_end, "\r\n");
}

TEST(IrdistStation, ValidatesItsKeysWithTheirLine) {
  DeviceSpec spec = VirtualStationRig::Spec("/dev/null", 5.0).devices[0];
  spec.file = "rig.yaml";
  spec.settings["trigger_widht_us"] = {"100", 17};
  try {
    FindDriver("irdist_station")->validate(spec);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.Line(), 17);
    EXPECT_NE(e.Message().find("trigger_width_us"), std::string::npos) << e.what();
  }
}

// move_timeout_ms 1e308 was cast to a count of milliseconds (undefined behaviour): within a day.
TEST(IrdistStation, AMoveTimeoutBeyondADayIsRefused) {
  DeviceSpec spec = VirtualStationRig::Spec("/dev/null", 5.0).devices[0];
  for (const char* value : {"1e308", "86400001", "0.5"}) {
    SCOPED_TRACE(value);
    spec.settings["move_timeout_ms"] = {value, 9};
    try {
      FindDriver("irdist_station")->validate(spec);
      ADD_FAILURE() << "accepted";
    } catch (const InputError& e) {
      EXPECT_NE(e.Message().find("move_timeout_ms must lie in [1, 86400000] ms"),
                std::string::npos)
          << e.what();
    }
  }
  spec.settings["move_timeout_ms"] = {"86400000", 9};
  EXPECT_NO_THROW(FindDriver("irdist_station")->validate(spec));
}

TEST(IrdistStation, ARebootIsADeviceRestartAlreadyRecovered) {
  VirtualStationRig rig(100.0);
  rig.station->Identify();
  rig.station->Home();
  rig.station->SetCurrent(400.0);
  rig.emulator.Reboot();
  try {
    rig.station->CheckAlive();
    ADD_FAILURE() << "no error";
  } catch (const DeviceRestarted& e) {
    EXPECT_TRUE(e.recovered());
  }
  EXPECT_DOUBLE_EQ(rig.world.Pose().bias_ma, 400.0);
}

TEST(IrdistStation, ARefusedMoveIsADeviceErrorWithTheStationsCode) {
  sim::EmulatorOptions options;
  options.slide.max = 2000.0;
  VirtualStationRig rig(100.0, options);
  rig.station->Identify();
  rig.station->Home();
  try {
    rig.station->MoveTo({2500.0, 0.0, 0.0});
    ADD_FAILURE() << "no error";
  } catch (const DeviceError& e) {
    EXPECT_EQ(e.device_code(), "-222");
    EXPECT_NE(std::string(e.what()).find("irdist_station on "), std::string::npos) << e.what();
  }
}

TEST(IrdistStation, FiresOnePulsePerFrame) {
  VirtualStationRig rig(100.0);
  rig.station->Identify();
  const std::uint64_t before = rig.world.TriggerPulses();
  for (int i = 0; i < 3; ++i) rig.station->Fire(i);
  EXPECT_EQ(rig.world.TriggerPulses() - before, 3u);
  EXPECT_STREQ(rig.station->TriggerCameraSource(), "Line1");
}

TEST(IrdistStation, TurningTheIredOffIsAcceptedInEStop) {
  VirtualStationRig rig(100.0);
  rig.station->Identify();
  rig.station->SetCurrent(300.0);
  rig.emulator.PressEmergencyStop();
  EXPECT_NO_THROW(rig.station->SetCurrent(0.0));
  EXPECT_THROW(rig.station->SetCurrent(100.0), DeviceError);
}

}  // namespace
}  // namespace irdist
