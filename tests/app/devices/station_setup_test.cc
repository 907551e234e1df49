// The station side of a run: which port each device of the rig is on (a virtual rig's ptys, a
// running sim's state file, `--port NAME=PATH`) and which camera input the run triggers. The
// station's own behaviour is tested in tests/station/, the commands over it in station_cmd_test.cc.
#include "app/devices/station_setup.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <map>
#include <string>

#include "app/inputs/errors.h"

namespace irdist {
namespace {

using Ports = std::map<std::string, std::string>;

const std::string kRigs = std::string(IRDIST_SOURCE_DIR) + "/recipes/rigs/";

// The irdist station box alone (virtual.yaml), and the composed lab of a Zaber slide, a FLIR
// pan-tilt head and a Keithley source under the camera's own software trigger (virtual-lab.yaml).
Rig SingleBox() { return LoadRig(kRigs + "virtual.yaml"); }
Rig ComposedLab() { return LoadRig(kRigs + "virtual-lab.yaml"); }

std::string UsageMessage(const Rig& rig, const std::string& arg) {
  try {
    ParsePortOverrides(rig, {arg});
  } catch (const UsageError& e) {
    return e.what();
  }
  return "";
}

TEST(VirtualDevicePorts, TheSingleBoxStationIsOnTheEmulatorsPty) {
  sim::VirtualRigInfo info;
  info.station_port = "/dev/pts/7";
  EXPECT_EQ(VirtualDevicePorts(SingleBox(), info), (Ports{{"station", "/dev/pts/7"}}));
  info.station_port.clear();  // no emulator yet: no port to give
  EXPECT_TRUE(VirtualDevicePorts(SingleBox(), info).empty());
}

TEST(VirtualDevicePorts, EachComposedDeviceIsOnItsOwnEmulatorsPty) {
  sim::VirtualRigInfo info;
  info.device_ports = {{"slide", "/dev/pts/3"}, {"head", "/dev/pts/4"}, {"source", "/dev/pts/5"}};
  EXPECT_EQ(VirtualDevicePorts(ComposedLab(), info), info.device_ports);
}

// A running sim's state file names its ports as `port.<device>`; a single-box sim only its
// `station_port`; its other keys are no ports.
TEST(PortsOfRunningSim, ReadsEachDevicesPortOrTheSingleBoxsStationPort) {
  RunningSim composed;
  composed.values = {{"port.slide", "/dev/pts/3"}, {"port.head", "/dev/pts/4"},
                     {"station_port", ""}, {"camera_id", "Aravis-Fake-1"},
                     {"trajectory_csv", "/tmp/t.csv"}};
  EXPECT_EQ(PortsOfRunningSim(composed), (Ports{{"slide", "/dev/pts/3"}, {"head", "/dev/pts/4"}}));
  RunningSim single_box;
  single_box.values = {{"station_port", "/dev/pts/9"}, {"camera_id", "Aravis-Fake-2"}};
  EXPECT_EQ(PortsOfRunningSim(single_box), (Ports{{"station", "/dev/pts/9"}}));
  EXPECT_TRUE(PortsOfRunningSim(RunningSim{}).empty());
}

// `--port NAME=PATH`: split at the first '=' (a by-id path may hold another), the name one of the
// rig's station devices.
TEST(ParsePortOverrides, NamesADeviceOfTheRigAndItsPath) {
  EXPECT_EQ(ParsePortOverrides(ComposedLab(), {"slide=/dev/ttyUSB0", "head=/dev/ttyUSB1"}),
            (Ports{{"slide", "/dev/ttyUSB0"}, {"head", "/dev/ttyUSB1"}}));
  EXPECT_EQ(ParsePortOverrides(ComposedLab(), {"source=/dev/serial/by-id/usb-K=2400"}),
            (Ports{{"source", "/dev/serial/by-id/usb-K=2400"}}));
  EXPECT_EQ(ParsePortOverrides(SingleBox(), {"station=/dev/ttyACM0"}),
            (Ports{{"station", "/dev/ttyACM0"}}));
  EXPECT_TRUE(ParsePortOverrides(ComposedLab(), {}).empty());
}

TEST(ParsePortOverrides, AMalformedArgumentOrAnUnknownDeviceIsAUsageError) {
  const Rig lab = ComposedLab();
  for (const std::string bad : {"slide", "=/dev/ttyUSB0", "slide=", ""}) {
    EXPECT_NE(UsageMessage(lab, bad).find("NAME=PATH"), std::string::npos) << "'" << bad << "'";
  }
  const std::string unknown = UsageMessage(lab, "camera=/dev/ttyUSB0");
  EXPECT_NE(unknown.find("no station device 'camera'"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find(lab.path), std::string::npos) << unknown;
  // A single-box rig's one device is "station": the message says so.
  const std::string single = UsageMessage(SingleBox(), "slide=/dev/ttyUSB0");
  EXPECT_NE(single.find("'station'"), std::string::npos) << single;
}

TEST(StationRunOptions, CarriesThePortsAndTheLog) {
  const std::string path = std::filesystem::temp_directory_path() /
                           ("irdist-station-setup-" + std::to_string(::getpid()) + ".log");
  {
    LineLog log(path);
    const Ports ports{{"slide", "/dev/ttyUSB0"}};
    const StationOptions options = StationRunOptions(ports, &log);
    EXPECT_EQ(options.ports, ports);
    EXPECT_EQ(options.log, &log);
    EXPECT_TRUE(options.off_at_exit);  // a run leaves the IRED off
  }
  std::filesystem::remove(path);
}

// The virtual camera's trigger input from an irdist station is Line1 whatever the rig file says;
// a software trigger, and any hardware rig, use the rig file's camera.trigger_source.
TEST(RigTriggerSource, TheVirtualStationsLineOrTheRigFilesSource) {
  Rig single_box = SingleBox();
  single_box.camera.trigger_source = "Line2";
  EXPECT_EQ(RigTriggerSource(single_box), "Line1");
  Rig lab = ComposedLab();
  EXPECT_EQ(RigTriggerSource(lab), "Software");
  Rig hardware = LoadRig(kRigs + "example-hardware.yaml");
  hardware.camera.trigger_source = "Line2";
  EXPECT_EQ(RigTriggerSource(hardware), "Line2");
}

}  // namespace
}  // namespace irdist
