#include "station/driver.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "base/input_error.h"

// The driver registry and the strict reading of a rig file's device entry (station/driver.h):
// the four device kinds of docs/devices/ are registered; a setting is a finite number, or an
// InputError naming the rig file, the line the key was written on and the key's full name.

namespace irdist {
namespace {

DeviceSpec Spec() {
  DeviceSpec spec;
  spec.name = "head";
  spec.driver = "flir_ptu";
  spec.file = "lab.yaml";
  spec.line = 12;
  spec.settings["pan_speed_deg_s"] = {"30.5", 15};
  spec.settings["mode"] = {"fast", 16};
  spec.settings["bad_number"] = {"12mm", 17};
  spec.settings["empty"] = {"", 18};
  spec.settings["not_finite"] = {"inf", 19};
  return spec;
}

TEST(DriverRegistry, TheFourDeviceKindsAreRegisteredUnderTheirRigFileNames) {
  const std::vector<std::string> names = DriverNames();
  for (const char* name : {"irdist_station", "zaber_ascii", "flir_ptu", "scpi_source"}) {
    EXPECT_NE(std::find(names.begin(), names.end(), name), names.end()) << name;
    const DriverInfo* info = FindDriver(name);
    ASSERT_NE(info, nullptr) << name;
    EXPECT_EQ(info->name, name);
    EXPECT_TRUE(static_cast<bool>(info->create)) << name;
  }
  EXPECT_TRUE(std::is_sorted(names.begin(), names.end()));
  EXPECT_EQ(FindDriver("zaber"), nullptr);
  EXPECT_EQ(FindDriver(""), nullptr);
}

// The PTU ends its replies with a lone CR (its manual's line end); the roles follow the devices.
TEST(DriverRegistry, EachDriverDeclaresTheRolesItsDeviceFills) {
  const auto roles = [](const char* name) { return FindDriver(name)->roles; };
  EXPECT_EQ(roles("scpi_source"), std::vector<std::string>{"source"});
  EXPECT_EQ(roles("flir_ptu"), std::vector<std::string>{"motion"});
  EXPECT_EQ(roles("zaber_ascii"), std::vector<std::string>{"motion"});
  const std::vector<std::string> station = roles("irdist_station");
  for (const char* role : {"motion", "source", "trigger"}) {
    EXPECT_NE(std::find(station.begin(), station.end(), role), station.end()) << role;
  }
  EXPECT_TRUE(FindDriver("flir_ptu")->cr_ends_reply);
}

DriverRegistration test_registration(DriverInfo{"test_kind", "\n", false, 19200, 250,
                                                {"trigger"}, "", nullptr, nullptr});

TEST(DriverRegistry, ARegistrationMakesItsDriverFindableWithItsDefaults) {
  const DriverInfo* info = FindDriver("test_kind");
  ASSERT_NE(info, nullptr);
  EXPECT_EQ(info->default_baud, 19200u);
  EXPECT_EQ(info->default_reply_timeout_ms, 250);
  EXPECT_EQ(info->roles, std::vector<std::string>{"trigger"});
  const std::vector<std::string> names = DriverNames();
  EXPECT_NE(std::find(names.begin(), names.end(), "test_kind"), names.end());
}

TEST(DeviceSpec, NumberReadsAFiniteNumberOrGivesTheFallbackForAMissingKey) {
  const DeviceSpec spec = Spec();
  EXPECT_EQ(spec.Number("pan_speed_deg_s", 1.0), 30.5);
  EXPECT_EQ(spec.Number("tilt_speed_deg_s", 12.25), 12.25);
  EXPECT_EQ(spec.Text("mode", "slow"), "fast");
  EXPECT_EQ(spec.Text("other", "slow"), "slow");
}

// "12mm", "" and "inf" are not finite numbers: refused at the key's own line, by full name.
TEST(DeviceSpec, NumberRefusesTextThatIsNotAFiniteNumberAtItsLine) {
  const DeviceSpec spec = Spec();
  const std::vector<std::pair<std::string, int>> bad = {
      {"bad_number", 17}, {"empty", 18}, {"not_finite", 19}, {"mode", 16}};
  for (const auto& [key, line] : bad) {
    try {
      spec.Number(key, 0.0);
      ADD_FAILURE() << key << " was read as a number";
    } catch (const InputError& e) {
      EXPECT_EQ(e.File(), "lab.yaml");
      EXPECT_EQ(e.Line(), line) << key;
      EXPECT_NE(std::string(e.what()).find("station.devices.head." + key), std::string::npos)
          << e.what();
      EXPECT_NE(std::string(e.what()).find("finite number"), std::string::npos) << e.what();
    }
  }
}

// An unknown key is refused at its line, naming the device, its driver and every valid key.
TEST(DeviceSpec, CheckKnownRefusesAnUnknownKeyListingTheValidOnes) {
  DeviceSpec spec = Spec();
  spec.settings.erase("bad_number");
  spec.settings.erase("empty");
  spec.settings.erase("not_finite");
  EXPECT_NO_THROW(spec.CheckKnown({"pan_speed_deg_s", "mode"}));
  try {
    spec.CheckKnown({"pan_speed_deg_s"});
    ADD_FAILURE() << "the unknown key 'mode' was accepted";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_EQ(e.Line(), 16);
    EXPECT_NE(what.find("unknown key 'mode'"), std::string::npos) << what;
    EXPECT_NE(what.find("station.devices.head"), std::string::npos) << what;
    EXPECT_NE(what.find("flir_ptu"), std::string::npos) << what;
    EXPECT_NE(what.find("driver, port, baud, reply_timeout_ms, axes, pan_speed_deg_s"),
              std::string::npos)
        << what;
  }
  DeviceSpec plain;
  plain.settings["x"] = {"1", 3};
  EXPECT_THROW(plain.CheckKnown({}), InputError);
}

}  // namespace
}  // namespace irdist
