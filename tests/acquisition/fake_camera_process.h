#pragma once
// Test helper: runs Aravis's own fake GigE Vision camera (arv-fake-gv-camera-0.8) on 127.0.0.1 as
// a child process, with a serial number of its own, and stops it at the end.
//
// It holds the loopback GVCP lock (tests/loopback_gvcp.h) while the camera runs, starts the camera
// and waits until it answers with the expected serial number.

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "acquisition/aravis_camera.h"
#include "tests/loopback_gvcp.h"

namespace irdist::testing {

class FakeCameraProcess {
 public:
  // extra_args: e.g. {"-r", "10"} to drop 1% of the packets.
  explicit FakeCameraProcess(std::string serial, std::vector<std::string> extra_args = {})
      : serial_(std::move(serial)) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    std::vector<std::string> args = {"arv-fake-gv-camera-0.8", "-i", "127.0.0.1", "-s", serial_};
    args.insert(args.end(), extra_args.begin(), extra_args.end());
    pid_ = ::fork();
    if (pid_ == 0) {
      std::vector<char*> argv;
      for (auto& arg : args) argv.push_back(arg.data());
      argv.push_back(nullptr);
      const int null_fd = ::open("/dev/null", O_WRONLY);
      if (null_fd >= 0) {
        ::dup2(null_fd, STDOUT_FILENO);
        ::dup2(null_fd, STDERR_FILENO);
      }
      ::execvp(argv[0], argv.data());
      ::_exit(127);
    }
    if (pid_ < 0) {
      Release();
      throw std::runtime_error("fork failed");
    }
    // Wait until it answers with our serial.
    while (true) {
      try {
        auto camera = AravisCamera::Open("127.0.0.1", serial_);
        break;
      } catch (const CameraError&) {
        int status = 0;
        if (::waitpid(pid_, &status, WNOHANG) == pid_) {
          pid_ = -1;
          Release();
          throw std::runtime_error("arv-fake-gv-camera-0.8 exited early");
        }
        if (std::chrono::steady_clock::now() > deadline) {
          Stop();
          throw std::runtime_error("arv-fake-gv-camera-0.8 does not answer on 127.0.0.1");
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
      }
    }
  }
  ~FakeCameraProcess() { Stop(); }
  FakeCameraProcess(const FakeCameraProcess&) = delete;
  FakeCameraProcess& operator=(const FakeCameraProcess&) = delete;

  const std::string& serial() const { return serial_; }

  void Stop() {
    if (pid_ > 0) {
      ::kill(pid_, SIGTERM);
      int status = 0;
      for (int i = 0; i < 50 && ::waitpid(pid_, &status, WNOHANG) == 0; ++i) {
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
      }
      if (::waitpid(pid_, &status, WNOHANG) == 0) {
        ::kill(pid_, SIGKILL);
        ::waitpid(pid_, &status, 0);
      }
      pid_ = -1;
    }
    Release();
  }

 private:
  void Release() { lock_.Release(); }
  LoopbackGvcpLock lock_;  // first member: taken before the camera starts
  std::string serial_;
  pid_t pid_ = -1;
};

}  // namespace irdist::testing
