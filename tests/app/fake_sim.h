#pragma once
// A stand-in for a running `irdist sim` in unit tests: a process of this user whose command line
// is `irdist sim` (a shell running a script named sim, so /proc shows argv "irdist", "sim"), and
// a pseudo-terminal of this user for its ports. Killed and reaped on destruction.

#include <pty.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace irdist::testing {

class FakeSim {
 public:
  explicit FakeSim(const std::filesystem::path& dir) {
    std::filesystem::create_directories(dir);
    std::ofstream(dir / "sim") << "while :; do sleep 1; done\n";  // no child outlives it long
    char name[256] = {0};
    if (::openpty(&master_, &slave_, name, nullptr, nullptr) == 0) pty_ = name;
    pid_ = ::fork();
    if (pid_ == 0) {
      if (::chdir(dir.c_str()) != 0) ::_exit(127);
      ::execl("/bin/sh", "irdist", "sim", static_cast<char*>(nullptr));
      ::_exit(127);
    }
    // Until the shell has replaced the forked copy, /proc shows this test's command line.
    for (int i = 0; i < 500 && !ShowsIrdistSim(); ++i) ::usleep(2000);
  }
  ~FakeSim() {
    if (pid_ > 0) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
    if (master_ >= 0) ::close(master_);
    if (slave_ >= 0) ::close(slave_);
  }
  FakeSim(const FakeSim&) = delete;
  FakeSim& operator=(const FakeSim&) = delete;

  long pid() const { return pid_; }
  const std::string& pty() const { return pty_; }

 private:
  bool ShowsIrdistSim() const {
    std::ifstream in("/proc/" + std::to_string(pid_) + "/cmdline", std::ios::binary);
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    return text == std::string("irdist\0sim\0", 11);
  }

  pid_t pid_ = -1;
  int master_ = -1, slave_ = -1;
  std::string pty_;
};

}  // namespace irdist::testing
