#pragma once
// The station side of the commands that drive a rig (calibrate, validate, plan --suggest,
// irdist station): which port each device is on (the rig file, a virtual rig's ptys, --port
// overrides), the station's options and the camera's trigger source.

#include <map>
#include <string>
#include <vector>

#include "app/inputs/rig.h"
#include "app/inputs/state_file.h"
#include "sim/virtual_rig.h"
#include "station/line_log.h"
#include "station/station.h"

namespace irdist {

// The ptys of a virtual rig's device emulators, by `station.devices` name.
std::map<std::string, std::string> VirtualDevicePorts(const Rig& rig,
                                                      const sim::VirtualRigInfo& info);
// The station devices' ports a running `irdist sim` wrote in its state file (`port.<device>`,
// or a single-box rig's `station_port` as device "station").
std::map<std::string, std::string> PortsOfRunningSim(const RunningSim& sim);
// `--port NAME=PATH` arguments (NAME a station.devices key; a single-box rig's device is "station").
// Throws UsageError on a malformed one or an unknown device.
std::map<std::string, std::string> ParsePortOverrides(const Rig& rig,
                                                      const std::vector<std::string>& args);
StationOptions StationRunOptions(const std::map<std::string, std::string>& ports, LineLog* log);
// The camera's TriggerSource for a run: the virtual camera's line from an irdist station is
// Line1; otherwise the rig file's camera.trigger_source (checked against the trigger role when the
// rig was loaded).
std::string RigTriggerSource(const Rig& rig);

}  // namespace irdist
