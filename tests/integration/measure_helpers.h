#pragma once
// What the measure integration tests share: the small calibration they make their model with, the
// JSON lines of `irdist measure --json`, and waiting for an `irdist sim` to run.

#include <fcntl.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "tests/integration/run_helpers.h"

namespace irdist::testing {

// A 3-distance x 4-angle x 2-current calibration on the virtual rig, fitted after recording
// (the measure tests and integration/calibrate_validate); `slides_mm` another list of distances.
inline std::string SmallCalibrationRecipe(const std::string& name,
                                          const std::string& slides_mm = "[1500, 2000, 2500]") {
  return "name: " + name + R"(
rig: virtual
after: fit
axes:
  slide_mm: )" + slides_mm + R"(
  theta_deg: [0, 10, 20, 30]
  bias_ma: [475, 500]
bracket:
  t_ref_ms: 8
  t_meas_ms: [30, 33, 36]
settle:
  after_move_ms: 200
  after_current_ms: 500
)";
}

// A test folder on a copy of recipes/rigs/virtual.yaml named virtual-fast (`dir`/rigs/) whose
// station emulator's slide has `slide_motion` in place of "speed: 200.0, accel: 400.0", with
// `dir`/runtime as XDG_RUNTIME_DIR (the sims' state files) and `dir`/calibration.yaml, the small
// calibration on that rig. Returns the rig file's path; "" when virtual.yaml's slide changed (or
// the environment cannot be set).
inline std::string FastSlideScratch(const std::string& dir, const std::string& slide_motion) {
  std::filesystem::create_directories(dir + "/runtime");
  std::filesystem::create_directories(dir + "/rigs");
  if (setenv("XDG_RUNTIME_DIR", (dir + "/runtime").c_str(), 1) != 0) return "";
  std::string rig = ReadAll(std::string(IRDIST_SOURCE_DIR) + "/recipes/rigs/virtual.yaml");
  const std::string slide = "speed: 200.0, accel: 400.0";
  const std::size_t at = rig.find(slide);
  if (at == std::string::npos) return "";
  const std::string path = dir + "/rigs/virtual-fast.yaml";
  WriteAll(path, rig.replace(at, slide.size(), slide_motion));
  std::string recipe = SmallCalibrationRecipe("fast-slide-calibration");
  WriteAll(dir + "/calibration.yaml", recipe.replace(recipe.find("rig: virtual"), 12,
                                                     "rig: virtual-fast"));
  return path;
}

// The JSON objects of an output (lines starting with '{'), parsed.
// Only whole lines count: a log read while its writer is still at work may end inside a line
// (stdout is flushed in blocks), and that part is left for the next read.
inline std::vector<YAML::Node> JsonLines(const std::string& output) {
  std::vector<YAML::Node> objects;
  std::istringstream in(output.substr(0, output.rfind('\n') + 1));
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty() && line[0] == '{') objects.push_back(YAML::Load(line));
  }
  return objects;
}

// Runs irdist with `args` (its stdout a pipe, its stderr to `log`), reads `count` lines of its
// stdout into *lines and then goes away (closes the pipe, as `head -n` does); returns the child's
// wait status (-1 when it could not be waited for).
inline int ReadLinesThenGoAway(const std::vector<std::string>& args, std::size_t count,
                               const std::string& log, std::vector<std::string>* lines) {
  int pipe_fds[2];
  if (pipe(pipe_fds) != 0) return -1;
  const pid_t pid = fork();
  if (pid == 0) {
    dup2(pipe_fds[1], STDOUT_FILENO);
    const int err = ::open(log.c_str(), O_CREAT | O_WRONLY | O_TRUNC, 0644);
    dup2(err, STDERR_FILENO);
    close(pipe_fds[0]);
    std::vector<char*> argv = {const_cast<char*>("irdist")};
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv(IrdistBinary().c_str(), argv.data());
    _exit(127);
  }
  close(pipe_fds[1]);
  FILE* reader = fdopen(pipe_fds[0], "r");
  char buffer[8192];
  while (lines->size() < count && std::fgets(buffer, sizeof(buffer), reader) != nullptr) {
    lines->emplace_back(buffer);
  }
  std::fclose(reader);  // the reader goes away, as head does
  int status = 0;
  return waitpid(pid, &status, 0) == pid ? status : -1;
}

// Waits until `irdist sim` announced its state file and runs; returns the file ("" on failure).
inline std::string WaitForSim(Child& sim, const std::string& log_path) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  std::smatch state;
  while (sim.Running() && std::chrono::steady_clock::now() < deadline) {
    const std::string log = ReadAll(log_path);
    if (log.find("Running until") != std::string::npos &&
        std::regex_search(log, state, std::regex(R"(state: (\S+\.yaml))")) &&
        std::filesystem::exists(state[1].str())) {
      return state[1].str();
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return "";
}

}  // namespace irdist::testing
