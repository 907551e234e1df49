#include "app/inputs/state_file.h"

#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <yaml-cpp/yaml.h>

#include <cerrno>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <ostream>
#include <sstream>

#include "base/regular_file.h"
#include "base/safe_file.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;

constexpr char kPrefix[] = "irdist-sim-";
constexpr std::int64_t kMaxStateBytes = 64 * 1024;

std::string EnvFolder(const char* name) {
  const char* value = std::getenv(name);  // NOLINT(concurrency-mt-unsafe)
  if (value == nullptr || *value != '/') return "";
  std::error_code ec;
  return fs::is_directory(value, ec) ? std::string(value) : std::string();
}

// The file's `key: value` pairs; false and `why` when it is not a flat YAML map of scalars.
bool ParseStateText(const std::string& text, std::map<std::string, std::string>* values,
                    std::string* why) {
  try {
    const YAML::Node root = YAML::Load(text);
    if (!root.IsMap()) {
      *why = "is not a YAML map";
      return false;
    }
    for (const auto& item : root) {
      if (!item.first.IsScalar() || !item.second.IsScalar()) {
        *why = "has a value that is not a plain scalar";
        return false;
      }
      (*values)[item.first.Scalar()] = item.second.Scalar();
    }
  } catch (const YAML::Exception& error) {
    *why = std::string("is not valid YAML (") + error.what() + ")";
    return false;
  }
  return true;
}

bool ParsePid(const std::string& text, long* pid) {
  char* end = nullptr;
  errno = 0;
  const long value = std::strtol(text.c_str(), &end, 10);
  if (text.empty() || errno != 0 || *end != '\0' || value <= 0) return false;
  *pid = value;
  return true;
}

// The file itself: a regular file of the user's, read whole. "" or why it is skipped.
std::string ReadOwnStateFile(const std::string& path, std::string* text) {
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0) return "cannot be examined";
  if (!S_ISREG(st.st_mode)) return "is not a regular file (a link, FIFO or folder)";
  if (st.st_uid != ::geteuid()) {
    return "belongs to user id " + std::to_string(st.st_uid) + ", not to you";
  }
  std::string why;
  if (!ReadRegularFile(path, kMaxStateBytes, text, &why)) return why;
  return "";
}

// Every port the state file names must be a pty of the user's. "" or why not.
std::string CheckPorts(const std::map<std::string, std::string>& values) {
  for (const auto& [key, value] : values) {
    if (key != "station_port" && key.rfind("port.", 0) != 0) continue;
    if (key == "station_port" && value.empty()) continue;
    const std::string why = NotOwnPty(value);
    if (!why.empty()) return key + " " + value + " " + why;
  }
  return "";
}

// The state file at `path` as a RunningSim, or "" in `*skip` for a dead process (the stale file
// of a sim that died: skipped silently) or the reason to warn.
std::optional<RunningSim> ReadState(const std::string& path, std::string* skip) {
  std::string text;
  *skip = ReadOwnStateFile(path, &text);
  if (!skip->empty()) return std::nullopt;
  RunningSim sim;
  sim.state_path = path;
  if (!ParseStateText(text, &sim.values, skip)) return std::nullopt;
  const auto pid = sim.values.find("pid");
  if (pid == sim.values.end() || !ParsePid(pid->second, &sim.pid)) {
    *skip = "has no valid pid";
    return std::nullopt;
  }
  if (::kill(static_cast<pid_t>(sim.pid), 0) != 0 && errno == ESRCH) return std::nullopt;
  if (!IsOwnIrdistSim(sim.pid)) {
    *skip = "names process " + std::to_string(sim.pid) + ", which is not an `irdist sim` of yours";
    return std::nullopt;
  }
  *skip = CheckPorts(sim.values);
  if (!skip->empty()) return std::nullopt;
  return sim;
}

}  // namespace

std::string RuntimeStateDir() {
  std::string dir = EnvFolder("XDG_RUNTIME_DIR");
  if (!dir.empty()) {
    dir += "/irdist";
  } else {
    std::string temp = EnvFolder("TMPDIR");
    if (temp.empty()) temp = "/tmp";
    dir = temp + "/irdist-" + std::to_string(::geteuid());
  }
  std::string why;
  if (!EnsurePrivateDir(dir, &why)) {
    throw StateFileError("the runtime folder " + dir + " " + why +
                         "; irdist keeps its state in a folder of yours only. Remove it (or "
                         "set XDG_RUNTIME_DIR to a folder of yours).");
  }
  return dir;
}

std::string SimStateYaml(const SimState& state) {
  YAML::Emitter out;
  out << YAML::BeginMap;
  out << YAML::Key << "pid" << YAML::Value << state.pid;
  out << YAML::Key << "rig" << YAML::Value << YAML::DoubleQuoted << state.rig;
  out << YAML::Key << "camera_id" << YAML::Value << YAML::DoubleQuoted << state.camera_id;
  out << YAML::Key << "camera_address" << YAML::Value << YAML::DoubleQuoted
      << state.camera_address;
  out << YAML::Key << "serial" << YAML::Value << YAML::DoubleQuoted << state.serial;
  out << YAML::Key << "station_port" << YAML::Value << YAML::DoubleQuoted << state.station_port;
  out << YAML::Key << "time_scale" << YAML::Value << state.time_scale;
  for (const auto& [name, port] : state.ports) {
    out << YAML::Key << "port." + name << YAML::Value << YAML::DoubleQuoted << port;
  }
  if (!state.trajectory_csv.empty()) {
    out << YAML::Key << "trajectory_csv" << YAML::Value << YAML::DoubleQuoted
        << state.trajectory_csv;
  }
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

std::string WriteSimState(const SimState& state) {
  const std::string path =
      RuntimeStateDir() + "/" + kPrefix + std::to_string(state.pid) + ".yaml";
  std::string why;
  if (!WriteFileAtomically(path, SimStateYaml(state), 0600, &why)) {
    throw StateFileError("the state file " + path + " " + why +
                         "; check the runtime folder (XDG_RUNTIME_DIR).");
  }
  return path;
}

std::vector<RunningSim> LiveSims(std::ostream& warn) {
  std::vector<RunningSim> sims;
  std::string dir;
  try {
    dir = RuntimeStateDir();
  } catch (const StateFileError& error) {
    warn << "warning: " << error.what() << " No running virtual rig is used.\n";
    return sims;
  }
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind(kPrefix, 0) != 0 || entry.path().extension() != ".yaml") continue;
    std::string skip;
    std::optional<RunningSim> sim = ReadState(entry.path().string(), &skip);
    if (sim) {
      sims.push_back(std::move(*sim));
    } else if (!skip.empty()) {
      warn << "warning: ignoring the state file " << entry.path().string() << ": it " << skip
           << ".\n";
    }
  }
  return sims;
}

bool IsOwnIrdistSim(long pid) {
  const std::string proc = "/proc/" + std::to_string(pid);
  struct stat st {};
  if (::stat(proc.c_str(), &st) != 0 || st.st_uid != ::geteuid()) return false;
  std::ifstream in(proc + "/cmdline", std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<std::string> argv;
  std::istringstream words(text);
  for (std::string word; std::getline(words, word, '\0');) argv.push_back(word);
  if (argv.empty() || fs::path(argv[0]).filename() != "irdist") return false;
  for (std::size_t i = 1; i < argv.size(); ++i) {
    if (!argv[i].empty() && argv[i][0] == '-') continue;
    return argv[i] == "sim";  // the command: the first argument that is not an option
  }
  return false;
}

std::string NotOwnPty(const std::string& port) {
  const std::string number = port.rfind("/dev/pts/", 0) == 0 ? port.substr(9) : "";
  if (number.empty() || number.find_first_not_of("0123456789") != std::string::npos) {
    return "is not a pseudo-terminal (/dev/pts/N)";
  }
  struct stat st {};
  if (::lstat(port.c_str(), &st) != 0) return "does not exist";
  if (!S_ISCHR(st.st_mode)) return "is not a terminal device";
  if (st.st_uid != ::geteuid()) {
    return "belongs to user id " + std::to_string(st.st_uid) + ", not to you";
  }
  return "";
}

}  // namespace irdist
