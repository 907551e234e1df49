#include "base/process.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>

extern char** environ;

namespace irdist {
namespace {

namespace fs = std::filesystem;

bool IsExecutableFile(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode) && ::access(path.c_str(), X_OK) == 0;
}

std::string AbsoluteOrDevNull(const std::string& path) {
  if (path.empty()) return "/dev/null";
  std::error_code ec;
  const fs::path absolute = fs::absolute(path, ec);
  return ec ? path : absolute.string();
}

// posix_spawn_file_actions_t released on every path out.
class FileActions {
 public:
  FileActions() { Check(posix_spawn_file_actions_init(&actions_), "init"); }
  ~FileActions() { posix_spawn_file_actions_destroy(&actions_); }
  FileActions(const FileActions&) = delete;
  FileActions& operator=(const FileActions&) = delete;

  void Open(int fd, const std::string& path, int flags) {
    Check(posix_spawn_file_actions_addopen(&actions_, fd, path.c_str(), flags, 0644), path);
  }
  void Chdir(const std::string& dir) {
    Check(posix_spawn_file_actions_addchdir_np(&actions_, dir.c_str()), dir);
  }
  const posix_spawn_file_actions_t* get() const { return &actions_; }

 private:
  static void Check(int rc, const std::string& what) {
    if (rc != 0)
      throw ProcessError("posix_spawn file action (" + what + ") failed: " + std::strerror(rc));
  }
  posix_spawn_file_actions_t actions_;
};

std::string Quoted(const std::vector<std::string>& argv) {
  std::string out;
  for (const std::string& a : argv) out += (out.empty() ? "[" : ", [") + a + "]";
  return out;
}

ProcessResult WaitFor(pid_t pid, const std::vector<std::string>& argv) {
  int status = 0;
  pid_t rc;
  do {
    rc = ::waitpid(pid, &status, 0);
  } while (rc < 0 && errno == EINTR);
  if (rc < 0)
    throw ProcessError("waiting for " + Quoted(argv) + " failed: " + std::strerror(errno));
  ProcessResult result;
  result.exited = WIFEXITED(status);
  if (result.exited) result.exit_code = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) result.signal = WTERMSIG(status);
  return result;
}

}  // namespace

std::string FindProgram(const std::string& name) {
  if (name.empty()) return "";
  if (name.find('/') != std::string::npos) return IsExecutableFile(name) ? name : "";
  const char* path = std::getenv("PATH");
  std::string dirs = path != nullptr ? path : "/usr/local/bin:/usr/bin:/bin";
  size_t start = 0;
  while (start <= dirs.size()) {
    size_t end = dirs.find(':', start);
    if (end == std::string::npos) end = dirs.size();
    const std::string dir = end > start ? dirs.substr(start, end - start) : ".";
    const std::string candidate = dir + "/" + name;
    if (IsExecutableFile(candidate)) return candidate;
    start = end + 1;
  }
  return "";
}

ProcessResult RunProgram(const ProcessSpec& spec) {
  IRDIST_CHECK(!spec.argv.empty());
  const std::string program = FindProgram(spec.argv.front());
  if (program.empty()) {
    throw ProcessError(spec.argv.front() + ": program not found on PATH; install it.");
  }
  if (!spec.working_dir.empty() && !fs::is_directory(spec.working_dir)) {
    throw ProcessError(spec.working_dir + ": no such folder to run " + Quoted(spec.argv) + " in.");
  }
  FileActions actions;
  // Outputs first, with absolute paths, so the change of folder does not move them.
  actions.Open(STDIN_FILENO, "/dev/null", O_RDONLY);
  actions.Open(STDOUT_FILENO, AbsoluteOrDevNull(spec.stdout_path), O_WRONLY | O_CREAT | O_TRUNC);
  actions.Open(STDERR_FILENO, AbsoluteOrDevNull(spec.stderr_path), O_WRONLY | O_CREAT | O_TRUNC);
  if (!spec.working_dir.empty()) actions.Chdir(spec.working_dir);
  std::vector<char*> argv;
  for (const std::string& a : spec.argv) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  pid_t pid = 0;
  const int rc = ::posix_spawn(&pid, program.c_str(), actions.get(), nullptr, argv.data(), environ);
  if (rc != 0) {
    throw ProcessError("cannot start " + Quoted(spec.argv) + ": " + std::strerror(rc) +
                       " (check the working folder and that the output files are writable).");
  }
  return WaitFor(pid, spec.argv);
}

}  // namespace irdist
