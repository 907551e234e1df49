#include "app/devices/sim_command.h"

#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <memory>
#include <ostream>
#include <thread>

#include "app/devices/station_setup.h"
#include "app/inputs/rig.h"
#include "app/inputs/rig_lookup.h"
#include "app/inputs/state_file.h"
#include "app/inputs/stop_signal.h"
#include "sim/virtual_rig.h"

namespace irdist {

namespace fs = std::filesystem;

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

void RunSim(const SimArgs& args, CommandIo io) {
  RequireValid(args, "sim");
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

}  // namespace irdist
