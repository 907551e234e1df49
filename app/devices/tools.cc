#include "app/devices/tools.h"
#include "app/devices/station_setup.h"

#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <map>
#include <ostream>
#include <sstream>
#include <thread>

#include "acquisition/aravis_camera.h"
#include "app/inputs/stop_signal.h"
#include "app/inputs/recipe.h"
#include "app/inputs/rig.h"
#include "sim/virtual_rig.h"

namespace irdist {

namespace fs = std::filesystem;

std::string ResolveRig(const std::string& spec) {
  if (fs::exists(spec)) return spec;
  std::string found = FindRigFile(spec, fs::current_path().string());
  if (found.empty()) {
    throw RecipeError(spec, 0, 0,
                      "no such rig: give a rig file (recipes/rigs/virtual.yaml) or the name of "
                      "one in recipes/rigs/ (e.g. virtual).");
  }
  return found;
}

namespace {

// Removes a file when it goes out of scope.
class RemoveOnExit {
 public:
  explicit RemoveOnExit(std::string path) : path_(std::move(path)) {}
  ~RemoveOnExit() {
    if (path_.empty()) return;
    std::error_code ignored;
    fs::remove(path_, ignored);
  }
  RemoveOnExit(const RemoveOnExit&) = delete;
  RemoveOnExit& operator=(const RemoveOnExit&) = delete;
  RemoveOnExit(RemoveOnExit&&) = delete;
  RemoveOnExit& operator=(RemoveOnExit&&) = delete;

 private:
  std::string path_;
};

// The trajectory file of the sim of process `pid`: irdist-sim-<pid>-trajectory.csv beside its state
// file in the private runtime folder ("" with a warning when that folder cannot be had). A file of
// that name left by an earlier process of the same pid (which died) is removed first: the log is
// created new.
std::string SimTrajectoryPath(long pid, std::ostream& err) {
  try {
    const std::string path =
        RuntimeStateDir() + "/irdist-sim-" + std::to_string(pid) + "-trajectory.csv";
    std::error_code ignored;
    fs::remove(path, ignored);  // a dead process's; a link is removed, never followed
    return path;
  } catch (const StateFileError& error) {
    err << "warning: " << error.what() << " The station's trajectory is not logged.\n";
    return "";
  }
}

}  // namespace

std::optional<RunningSim> FindRunningSim(const std::string& rig_path, std::ostream& warn) {
  for (RunningSim& sim : LiveSims(warn)) {
    const auto rig = sim.values.find("rig");
    std::error_code same_error;
    if (rig != sim.values.end() && fs::equivalent(rig->second, rig_path, same_error)) return sim;
  }
  return std::nullopt;
}

void RunSim(const SimArgs& args, CommandIo io) {
  const std::string rig_path = ResolveRig(args.rig);
  const Rig rig = LoadRig(rig_path);
  PrintRigNotes(rig, io.err);
  if (rig.kind != RigKind::kVirtual) {
    throw RecipeError(rig_path, 0, 0,
                      "is a hardware rig (kind: hardware); 'irdist sim' runs "
                      "rigs of kind virtual only.");
  }
  SignalGuard guard;
  sim::VirtualRigOverrides overrides;
  if (args.time_scale > 0.0) overrides.time_scale = args.time_scale;
  const std::string trajectory_path = SimTrajectoryPath(getpid(), io.err);
  if (!trajectory_path.empty()) overrides.trajectory_csv = trajectory_path;
  RemoveOnExit remove_trajectory(trajectory_path);
  std::unique_ptr<sim::VirtualRig> virtual_rig = sim::VirtualRig::Start(rig_path, overrides);
  const sim::VirtualRigInfo& info = virtual_rig->Info();

  SimState state{getpid(),         fs::absolute(rig_path).string(), info.camera_id,
                 info.camera_address, info.serial, info.station_port, info.time_scale,
                 VirtualDevicePorts(rig, info), info.trajectory_csv};
  std::string state_path;
  try {
    state_path = WriteSimState(state);
  } catch (const StateFileError& error) {
    io.err << "warning: " << error.what() << " measure, snap, view and station will not find "
           << "this rig.\n";
  }
  RemoveOnExit remove_state(state_path);
  io.out << "camera: " << info.camera_id << " " << info.camera_address << " serial " << info.serial
         << "\n";
  io.out << "station: " << info.station_port << "\n";
  io.out << "time scale: " << info.time_scale << "\ntrajectory: "
         << (info.trajectory_csv.empty() ? "not logged (see the warning)" : info.trajectory_csv)
         << "\nstate: " << (state_path.empty() ? "not written (see the warning)" : state_path)
         << "\nRunning until Ctrl-C (SIGINT or SIGTERM).\n"
         << std::flush;
  while (!StopRequested().load()) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  virtual_rig->Stop();
  io.out << "virtual rig stopped\n" << std::flush;
}

void RunDevices(const DevicesArgs& args, CommandIo io) {
  io.out << "Virtual rigs (irdist sim):\n";
  int rigs = 0;
  for (const RunningSim& sim : LiveSims(io.err)) {
    const auto value = [&sim](const char* key) {
      const auto found = sim.values.find(key);
      return found == sim.values.end() ? std::string("?") : found->second;
    };
    ++rigs;
    io.out << "  pid " << sim.pid << ": camera " << value("camera_id") << " at "
           << value("camera_address") << " serial " << value("serial") << ", station "
           << value("station_port") << ", time scale " << value("time_scale") << "\n";
  }
  std::error_code error;
  if (rigs == 0) io.out << "  none\n";

  io.out << "Serial ports:\n";
  int ports = 0;
  for (const auto& entry : fs::directory_iterator("/dev", error)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("ttyUSB", 0) == 0 || name.rfind("ttyACM", 0) == 0) {
      io.out << "  " << entry.path().string() << "\n";
      ++ports;
    }
  }
  if (ports == 0) io.out << "  none\n";

  if (!args.discover) {
    io.out << "Cameras: not searched (discovery broadcasts on every network interface; add "
              "--discover)\n";
    return;
  }
  io.out << "Cameras:\n";
  const std::vector<DeviceInfo> cameras = ListCameras();
  for (const DeviceInfo& d : cameras) {
    io.out << "  " << d.id << " (" << d.protocol << ") " << d.vendor << " " << d.model << " serial "
           << d.serial << (d.address.empty() ? "" : " at " + d.address) << "\n";
  }
  if (cameras.empty()) io.out << "  none\n";
}

}  // namespace irdist
