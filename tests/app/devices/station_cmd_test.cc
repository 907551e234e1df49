#include "app/devices/station_cmd.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <thread>

#include "app/inputs/errors.h"
#include "sim/device_emulator.h"
#include "sim/station_emulator.h"
#include "sim/world.h"
#include "station/serial_transport.h"

namespace irdist {
namespace {

// `irdist station` on the virtual rig's file with its station's port given by --port (the
// emulator in this process; no camera is started).
class StationCommand : public ::testing::Test {
 protected:
  StationCommand() : world_(100.0), emulator_(world_, sim::EmulatorOptions{}) {
    port_ = emulator_.Start();
  }
  std::string Run(const std::string& action, std::vector<double> values = {}) {
    StationArgs args;
    args.rig = std::string(IRDIST_SOURCE_DIR) + "/recipes/rigs/virtual.yaml";
    args.action = action;
    args.values = std::move(values);
    args.ports = {"station=" + port_};
    std::ostringstream out, err;
    RunStation(args, {out, err});
    err_ = err.str();
    return out.str();
  }
  sim::World world_;
  sim::StationEmulator emulator_;
  std::string err_;  // the last command's stderr
  std::string port_;
};

TEST_F(StationCommand, MovesHomingFirstAndReportsThePose) {
  const std::string out = Run("move", {1800.0, 5.0, 0.0});
  EXPECT_NEAR(world_.Pose().slide_mm, 1800.0, 1e-6);
  EXPECT_NEAR(world_.Pose().pan_deg, 5.0, 1e-6);
  EXPECT_NE(out.find("position: slide 1800.00 mm, pan 5.00 deg"), std::string::npos) << out;
}

// A move on a station that was never homed since it powered up says so and names the command
// that homes it; once homed, a later move does not home again.
TEST_F(StationCommand, AMoveBeforeHomeSaysItHomesFirstAndNamesTheHomeCommand) {
  Run("move", {1500.0, 0.0, 0.0});
  EXPECT_NE(err_.find("not homed since power-up: homing first"), std::string::npos) << err_;
  EXPECT_NE(err_.find("'irdist station --rig " + std::string(IRDIST_SOURCE_DIR) +
                      "/recipes/rigs/virtual.yaml home'"),
            std::string::npos)
      << err_;
  Run("move", {1600.0, 0.0, 0.0});
  EXPECT_EQ(err_.find("homing first"), std::string::npos) << err_;
  EXPECT_NEAR(world_.Pose().slide_mm, 1600.0, 1e-6);
}

// Regression: two commands on one port both moved the station, each printing its own
// target. A port in use (here held by this process, as a calibrate would hold it) is refused
// before anything is sent, naming the holder.
TEST_F(StationCommand, APortInUseIsRefusedNamingItsHolder) {
  SerialTransport holder(port_);
  const double slide_mm = world_.Pose().slide_mm;
  try {
    Run("move", {1800.0, 5.0, 0.0});
    FAIL() << "a second command drove a port in use";
  } catch (const LinkError& e) {
    EXPECT_NE(std::string(e.what()).find("in use by process " + std::to_string(getpid())),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(world_.Pose().slide_mm, slide_mm);
  EXPECT_FALSE(world_.Pose().moving);
}

TEST_F(StationCommand, TheCurrentStaysOnUntilOff) {
  Run("current", {300.0});
  EXPECT_DOUBLE_EQ(world_.Pose().bias_ma, 300.0);  // the command ended; the IRED is still on
  Run("off");
  EXPECT_DOUBLE_EQ(world_.Pose().bias_ma, 0.0);
}

TEST_F(StationCommand, RefusesAPoseOutsideTheRigsLimitsBeforeMoving) {
  EXPECT_THROW(Run("move", {5000.0, 0.0, 0.0}), RecipeError);
  EXPECT_THROW(Run("move", {2000.0}), UsageError);
  EXPECT_FALSE(world_.Pose().moving);
}

// Regression: `station move 1e308` printed a 190-digit number.
TEST_F(StationCommand, AHugeTargetIsRefusedInPlainNumbers) {
  try {
    Run("move", {1e308, 0.0, 0.0});
    FAIL() << "moved";
  } catch (const RecipeError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("slide_mm 1e+308 is outside station.limits [1000, 3500]"),
              std::string::npos)
        << what;
    EXPECT_LT(what.size(), 200u) << what;
  }
  EXPECT_FALSE(world_.Pose().moving);
}

TEST_F(StationCommand, AnUnknownDeviceInPortIsAUsageError) {
  StationArgs args;
  args.rig = std::string(IRDIST_SOURCE_DIR) + "/recipes/rigs/virtual.yaml";
  args.action = "status";
  args.ports = {"slide=" + port_};
  std::ostringstream out, err;
  EXPECT_THROW(RunStation(args, {out, err}), UsageError);
}

// `irdist station` on the virtual lab (Zaber slide, FLIR PTU head, Keithley 2400 source), each
// device's emulator in this process on its own pty, its port given by --port.
class LabStationCommand : public ::testing::Test {
 protected:
  LabStationCommand() : world_(100.0) {
    const std::string rig = RigPath();
    std::ifstream in(rig);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    for (const char* name : {"slide", "head", "source"}) {
      const std::string driver = name == std::string("slide")  ? "zaber_ascii"
                                 : name == std::string("head") ? "flir_ptu"
                                                               : "scpi_source";
      emulators_[name] = sim::FindEmulator(driver)->create(world_, {name, driver, rig, text, 1});
      ports_.push_back(std::string(name) + "=" + emulators_[name]->Start());
    }
  }
  static std::string RigPath() {
    return std::string(IRDIST_SOURCE_DIR) + "/recipes/rigs/virtual-lab.yaml";
  }
  std::string Run(const std::string& action, std::vector<double> values = {}) {
    StationArgs args;
    args.rig = RigPath();
    args.action = action;
    args.values = std::move(values);
    args.ports = ports_;
    std::ostringstream out, err;
    RunStation(args, {out, err});
    return out.str();
  }
  sim::World world_;
  std::map<std::string, std::unique_ptr<sim::DeviceEmulator>> emulators_;
  std::vector<std::string> ports_;
};

// The SourceMeter holds the current after the command ends, and a later command (status) does
// not reset it; only `off` switches it off.
TEST_F(LabStationCommand, TheSourceMeterHoldsTheCurrentUntilOff) {
  Run("current", {500.0});
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  EXPECT_NEAR(world_.Pose().bias_ma, 500.0, 1e-6);
  const std::string status = Run("status");
  EXPECT_NE(status.find("current: 500.0"), std::string::npos) << status;
  EXPECT_NEAR(world_.Pose().bias_ma, 500.0, 1e-6);
  Run("off");
  EXPECT_DOUBLE_EQ(world_.Pose().bias_ma, 0.0);
}

}  // namespace
}  // namespace irdist
