#pragma once
// Test helper: an Xvfb virtual display for the life of the object, on a display number Xvfb picks
// itself (-displayfd), so tests in parallel never share one. running() is false when the machine
// has no Xvfb (the test then skips). display() is ":N" for DISPLAY.

#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <string>
#include <vector>

extern char** environ;

namespace irdist::testing {

class Xvfb {
 public:
  Xvfb() {
    for (const char* path : {"/usr/bin/Xvfb", "/usr/local/bin/Xvfb"}) {
      if (std::filesystem::exists(path)) binary_ = path;
    }
    int fds[2];
    if (binary_.empty() || ::pipe(fds) != 0) return;
    std::vector<std::string> words = {binary_, "-displayfd", std::to_string(fds[1]), "-screen",
                                      "0", "1024x768x24", "-nolisten", "tcp"};
    std::vector<char*> argv;
    for (std::string& w : words) argv.push_back(w.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addclose(&actions, fds[0]);
    if (posix_spawn(&pid_, binary_.c_str(), &actions, nullptr, argv.data(), environ) != 0) {
      pid_ = -1;
    }
    posix_spawn_file_actions_destroy(&actions);
    ::close(fds[1]);
    // Xvfb writes the display number and a newline once it accepts clients.
    std::string number;
    char c = 0;
    while (pid_ > 0 && ::read(fds[0], &c, 1) == 1 && c != '\n') number += c;
    ::close(fds[0]);
    if (!number.empty()) display_ = ":" + number;
  }
  ~Xvfb() {
    if (pid_ > 0) {
      ::kill(pid_, SIGTERM);
      ::waitpid(pid_, nullptr, 0);
    }
  }
  Xvfb(const Xvfb&) = delete;
  Xvfb& operator=(const Xvfb&) = delete;
  bool running() const { return pid_ > 0 && !display_.empty(); }
  const std::string& display() const { return display_; }

 private:
  std::string binary_;
  pid_t pid_ = -1;
  std::string display_;
};

}  // namespace irdist::testing
