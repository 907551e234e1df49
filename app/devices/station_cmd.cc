#include "app/devices/station_cmd.h"

#include <cstdio>
#include <optional>
#include <ostream>

#include "app/devices/station_setup.h"
#include "app/inputs/rig.h"
#include "app/inputs/rig_lookup.h"
#include "station/conformance.h"
#include "station/serial_transport.h"

namespace irdist {
namespace {

// The ports a running `irdist sim` of this rig file wrote in its state file.
std::map<std::string, std::string> RunningSimPorts(const Rig& rig, std::ostream& warn) {
  const std::optional<RunningSim> sim = FindRunningSim(rig.path, warn);
  return sim ? PortsOfRunningSim(*sim) : std::map<std::string, std::string>{};
}

std::map<std::string, std::string> PortsFor(const Rig& rig, const StationArgs& args,
                                            std::ostream& warn) {
  std::map<std::string, std::string> ports;
  if (rig.kind == RigKind::kVirtual) ports = RunningSimPorts(rig, warn);
  for (const auto& [name, port] : ParsePortOverrides(rig, args.ports)) ports[name] = port;
  for (const DeviceSpec& d : rig.station.composition.devices) {
    if (ports.count(d.name) == 0 && d.port == "auto") {
      throw UsageError("the port of station device '" + d.name + "' is unknown: start the " +
                       "virtual rig first ('irdist sim " + rig.path + "' in another terminal) " +
                       "or pass --port " + d.name + "=PATH");
    }
  }
  return ports;
}

void CheckCount(const StationArgs& args, std::size_t count, const char* usage) {
  if (args.values.size() != count) {
    throw UsageError(std::string("station ") + args.action + " takes " + usage);
  }
}

void CheckWithin(const Rig& rig, const char* what, double value, const AxisRange& range) {
  if (!range.Contains(value)) {
    char text[200];  // %g: 1e308 prints as 1e+308, never as 309 digits
    std::snprintf(text, sizeof(text), "%s %.10g is outside station.limits [%.10g, %.10g]", what,
                  value, range.min, range.max);
    throw RecipeError(rig.path, 0, 0, text);
  }
}

void PrintStatus(Station& station, std::ostream& out) {
  for (const auto& [name, state] : station.States()) {
    out << name << ": " << MotionStateName(state) << "\n";
  }
  const StationPosition p = station.Position();
  const SourceReading reading = station.MeasureCurrent();
  char line[200];
  std::snprintf(line, sizeof(line),
                "position: slide %.2f mm, pan %.2f deg, tilt %.2f deg\ncurrent: %.2f mA "
                "measured%s\n",
                p.slide_mm, p.pan_deg, p.tilt_deg, reading.current_ma,
                reading.in_compliance ? " (in compliance)" : "");
  out << line;
}

// A move needs homed axes: a device that reports no home reference (never homed since it powered
// up; a PTU cannot tell, so it is homed once per command) is homed first, and the user told so.
void HomeFirstIfUnhomed(const StationArgs& args, Station& station, std::ostream& err) {
  station.CheckReadyToStart();
  if (station.homed()) return;
  std::string unhomed;
  for (const auto& [name, state] : station.States()) {
    if (state != MotionState::kIdle) unhomed += (unhomed.empty() ? "" : ", ") + name;
  }
  err << "station move: " << unhomed << " not homed since power-up: homing first (as 'irdist "
      << "station --rig " << args.rig << " home' does), then moving\n";
  err.flush();
  station.Home();
}

void Move(const Rig& rig, const StationArgs& args, Station& station, std::ostream& err) {
  CheckCount(args, 3, "SLIDE_MM PAN_DEG TILT_DEG");
  const StationPosition target{args.values[0], args.values[1], args.values[2]};
  CheckWithin(rig, "slide_mm", target.slide_mm, rig.station.limits.slide_mm);
  CheckWithin(rig, "pan_deg", target.pan_deg, rig.station.limits.pan_deg);
  CheckWithin(rig, "tilt_deg", target.tilt_deg, rig.station.limits.tilt_deg);
  HomeFirstIfUnhomed(args, station, err);
  station.MoveTo(target);
}

void SetCurrent(const Rig& rig, const StationArgs& args, Station& station) {
  CheckCount(args, 1, "MA");
  CheckWithin(rig, "bias_ma", args.values[0], rig.station.limits.bias_ma);
  station.SetCurrent(args.values[0]);
  station.MeasureCheckedCurrent();
}

}  // namespace

void RunStation(const StationArgs& args, CommandIo io) {
  RequireValid(args, "station");
  const Rig rig = LoadRig(ResolveRig(args.rig));
  PrintRigNotes(rig, io.err);
  StationOptions options = StationRunOptions(PortsFor(rig, args, io.err), nullptr);
  options.off_at_exit = false;  // `current` leaves the IRED on; `off` switches it off
  Station station(rig.station.composition, options);
  station.Identify();
  io.err << station.IdentityBrief() << "\n";
  if (args.action == "move") {
    Move(rig, args, station, io.err);
  } else if (args.action == "current") {
    SetCurrent(rig, args, station);
  } else if (args.action == "off") {
    CheckCount(args, 0, "no value");
    station.Off();
    station.Stop();
  } else if (args.action == "home") {
    CheckCount(args, 0, "no value");
    station.Home();
  } else if (args.action != "status") {
    throw UsageError("station: unknown action '" + args.action +
                     "'; valid: move, current, off, home, status");
  }
  PrintStatus(station, io.out);
}

void RunStationTest(const StationTestArgs& args, CommandIo io) {
  RequireValid(args, "station-test");
  SerialOptions serial;
  serial.baud = static_cast<unsigned int>(args.baud);
  serial.origin = "the PORT and --baud of irdist station-test";
  SerialTransport transport(args.port, serial);
  const ConformanceReport report = RunConformance(transport, ConformanceOptions{});
  io.out << report.Table();
  if (!report.Passed()) {
    throw CheckFailedError(args.port + ": " + std::to_string(report.Failures()) +
                           " conformance check(s) failed (table above); see "
                           "docs/station-protocol.md");
  }
}

}  // namespace irdist
