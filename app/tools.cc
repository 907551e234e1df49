#include "app/tools.h"
#include "app/station_setup.h"

#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <ostream>
#include <sstream>
#include <thread>

#include "acquisition/aravis_camera.h"
#include "app/recipe.h"
#include "app/rig.h"
#include "app/run.h"
#include "sim/virtual_rig.h"

namespace irdist {

namespace fs = std::filesystem;

std::string SimStateDir() {
  const char* runtime = std::getenv("XDG_RUNTIME_DIR");  // NOLINT(concurrency-mt-unsafe)
  if (runtime != nullptr && *runtime != '\0' && fs::is_directory(runtime)) return runtime;
  return "/tmp";
}

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

}  // namespace

std::map<std::string, std::string> ReadFlatYaml(const std::string& path) {
  std::map<std::string, std::string> values;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    const size_t colon = line.find(':');
    if (colon == std::string::npos) continue;
    std::string value = line.substr(colon + 1);
    while (!value.empty() && (value.front() == ' ' || value.front() == '"')) value.erase(0, 1);
    while (!value.empty() && (value.back() == ' ' || value.back() == '"')) value.pop_back();
    values[line.substr(0, colon)] = value;
  }
  return values;
}

std::optional<RunningSim> FindRunningSim(const std::string& rig_path) {
  std::error_code error;
  for (const auto& entry : fs::directory_iterator(SimStateDir(), error)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("irdist-sim-", 0) != 0 || entry.path().extension() != ".yaml") continue;
    RunningSim sim{0, entry.path().string(), ReadFlatYaml(entry.path().string())};
    const auto pid = sim.values.find("pid");
    const auto rig = sim.values.find("rig");
    if (pid == sim.values.end() || rig == sim.values.end()) continue;
    std::error_code same_error;
    if (!fs::equivalent(rig->second, rig_path, same_error)) continue;
    sim.pid = std::atol(pid->second.c_str());
    const bool alive = sim.pid > 0 && (kill(static_cast<pid_t>(sim.pid), 0) == 0 || errno == EPERM);
    if (!alive) continue;  // the stale file of a rig that died
    return sim;
  }
  return std::nullopt;
}

void RunSim(const SimArgs& args, CommandIo io) {
  const std::string rig_path = ResolveRig(args.rig);
  const Rig rig = LoadRig(rig_path);
  if (rig.kind != RigKind::kVirtual) {
    throw RecipeError(rig_path, 0, 0,
                      "is a hardware rig (kind: hardware); 'irdist sim' runs "
                      "rigs of kind virtual only.");
  }
  SignalGuard guard;
  sim::VirtualRigOverrides overrides;
  if (args.time_scale > 0.0) overrides.time_scale = args.time_scale;
  std::unique_ptr<sim::VirtualRig> virtual_rig = sim::VirtualRig::Start(rig_path, overrides);
  const sim::VirtualRigInfo& info = virtual_rig->Info();

  const std::string state_path =
      SimStateDir() + "/irdist-sim-" + std::to_string(getpid()) + ".yaml";
  RemoveOnExit remove_state(state_path);
  {
    std::ofstream state(state_path);
    state << "pid: " << getpid() << "\nrig: \"" << fs::absolute(rig_path).string()
          << "\"\ncamera_id: \"" << info.camera_id << "\"\ncamera_address: \""
          << info.camera_address << "\"\nserial: \"" << info.serial << "\"\nstation_port: \""
          << info.station_port << "\"\ntime_scale: " << info.time_scale << "\n";
    for (const auto& [name, port] : VirtualDevicePorts(rig, info)) {
      state << "port." << name << ": \"" << port << "\"\n";
    }
  }
  io.out << "camera: " << info.camera_id << " " << info.camera_address << " serial " << info.serial
         << "\n";
  io.out << "station: " << info.station_port << "\n";
  io.out << "time scale: " << info.time_scale << "\nstate: " << state_path
         << "\nRunning until Ctrl-C (SIGINT or SIGTERM).\n"
         << std::flush;
  while (!StopRequested().load()) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  virtual_rig->Stop();
  io.out << "virtual rig stopped\n" << std::flush;
}

void RunDevices(const DevicesArgs& args, CommandIo io) {
  io.out << "Virtual rigs (irdist sim):\n";
  int rigs = 0;
  std::error_code error;
  for (const auto& entry : fs::directory_iterator(SimStateDir(), error)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("irdist-sim-", 0) != 0 || entry.path().extension() != ".yaml") continue;
    const auto values = ReadFlatYaml(entry.path().string());
    const auto pid = values.find("pid");
    if (pid == values.end()) continue;
    const pid_t id = static_cast<pid_t>(std::atoll(pid->second.c_str()));
    if (id <= 0 || kill(id, 0) != 0) continue;  // stale file of a rig that died
    ++rigs;
    io.out << "  pid " << id << ": camera " << values.at("camera_id") << " at "
           << values.at("camera_address") << " serial " << values.at("serial") << ", station "
           << values.at("station_port") << ", time scale " << values.at("time_scale") << "\n";
  }
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
