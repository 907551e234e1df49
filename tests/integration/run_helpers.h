#pragma once
// Helpers of the integration tests: run the built irdist binary as a child process (its output to a
// log file), signal it, wait for it, and small file utilities. Every test that starts a virtual
// rig (through the binary) holds the loopback GVCP lock (tests/loopback_gvcp.h)
// for as long as the child may run.

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace irdist::testing {

inline std::string IrdistBinary() { return std::string(IRDIST_BINARY_DIR) + "/app/irdist"; }

// A fresh, empty scratch folder for one test.
inline std::string ScratchDir(const std::string& name) {
  const std::string dir = std::string(IRDIST_BINARY_DIR) + "/tests/integration/scratch/" + name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

inline std::string ReadAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

inline void WriteAll(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
}

// Lines in a file (0 when missing).
inline int CountLines(const std::string& path) {
  std::ifstream in(path);
  int n = 0;
  std::string line;
  while (std::getline(in, line)) ++n;
  return n;
}

// irdist running as a child process; stdout and stderr go to `log_path`.
class Child {
 public:
  Child(const std::vector<std::string>& args, const std::string& log_path) {
    pid_ = fork();
    if (pid_ == 0) {
      const int fd = ::open(log_path.c_str(), O_CREAT | O_WRONLY | O_TRUNC, 0644);
      if (fd >= 0) {
        dup2(fd, STDOUT_FILENO);
        dup2(fd, STDERR_FILENO);
      }
      std::vector<std::string> words = {IrdistBinary()};
      words.insert(words.end(), args.begin(), args.end());
      std::vector<char*> argv;
      for (std::string& w : words) argv.push_back(w.data());
      argv.push_back(nullptr);
      execv(argv[0], argv.data());
      _exit(127);
    }
  }
  ~Child() {
    if (pid_ > 0 && !reaped_) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
  }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;

  void Signal(int signal) { kill(pid_, signal); }
  bool Running() {
    if (reaped_) return false;
    int status = 0;
    const pid_t r = waitpid(pid_, &status, WNOHANG);
    if (r == pid_) {
      reaped_ = true;
      status_ = status;
      return false;
    }
    return true;
  }
  // Waits up to `timeout`; returns the exit code, 128 + signal when killed, -1 on timeout.
  int Wait(std::chrono::seconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (Running()) {
      if (std::chrono::steady_clock::now() > deadline) return -1;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    if (WIFEXITED(status_)) return WEXITSTATUS(status_);
    if (WIFSIGNALED(status_)) return 128 + WTERMSIG(status_);
    return -1;
  }

 private:
  pid_t pid_ = -1;
  bool reaped_ = false;
  int status_ = 0;
};

// Runs irdist to completion (at most `timeout`); returns its exit code, the output in *output.
inline int RunIrdist(const std::vector<std::string>& args, const std::string& log_path,
                     std::string* output = nullptr,
                     std::chrono::seconds timeout = std::chrono::seconds(120)) {
  Child child(args, log_path);
  const int code = child.Wait(timeout);
  if (output != nullptr) *output = ReadAll(log_path);
  return code;
}

}  // namespace irdist::testing
