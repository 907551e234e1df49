#pragma once
// Test helper: runs Aravis's own fake GigE Vision camera (arv-fake-gv-camera-0.8) on 127.0.0.1 as
// a child process, with a serial number of its own, and stops it at the end.
//
// Only one fake camera can own 127.0.0.1:3956, and other tests of the project may start one too.
// The helper therefore (1) takes an exclusive flock on /tmp/irdist-gvcp-127.0.0.1.lock, the
// project's convention for "I own the loopback GVCP port", (2) waits until the UDP port is really
// free, (3) starts the camera and waits until it answers with the expected serial number.

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "acquisition/aravis_camera.h"

namespace irdist::testing {

inline bool LoopbackGvcpPortFree() {
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  if (fd < 0) return false;
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(3956);
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  const bool free = ::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)) == 0;
  ::close(fd);
  return free;
}

// Holds the project's loopback-GVCP lock and waits until UDP 127.0.0.1:3956 is free, for tests
// that start an in-process camera (the virtual rig) on 127.0.0.1.
class LoopbackGvcpLock {
 public:
  LoopbackGvcpLock() {
    fd_ = ::open("/tmp/irdist-gvcp-127.0.0.1.lock", O_CREAT | O_RDWR | O_CLOEXEC, 0666);
    if (fd_ < 0 || ::flock(fd_, LOCK_EX) != 0) {
      throw std::runtime_error("cannot lock /tmp/irdist-gvcp-127.0.0.1.lock");
    }
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (!LoopbackGvcpPortFree()) {
      if (std::chrono::steady_clock::now() > deadline) {
        ::close(fd_);
        throw std::runtime_error("UDP 127.0.0.1:3956 stays busy: another camera is running");
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  }
  ~LoopbackGvcpLock() {
    if (fd_ >= 0) ::close(fd_);  // closing releases the flock
  }
  LoopbackGvcpLock(const LoopbackGvcpLock&) = delete;
  LoopbackGvcpLock& operator=(const LoopbackGvcpLock&) = delete;

 private:
  int fd_ = -1;
};

class FakeCameraProcess {
 public:
  // extra_args: e.g. {"-r", "10"} to drop 1% of the packets.
  explicit FakeCameraProcess(std::string serial, std::vector<std::string> extra_args = {})
      : serial_(std::move(serial)) {
    lock_fd_ = ::open("/tmp/irdist-gvcp-127.0.0.1.lock", O_CREAT | O_RDWR | O_CLOEXEC, 0666);
    if (lock_fd_ < 0 || ::flock(lock_fd_, LOCK_EX) != 0) {
      throw std::runtime_error("cannot lock /tmp/irdist-gvcp-127.0.0.1.lock");
    }
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (!LoopbackGvcpPortFree()) {
      if (std::chrono::steady_clock::now() > deadline) {
        Release();
        throw std::runtime_error("UDP 127.0.0.1:3956 stays busy: another fake camera is running");
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
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
  void Release() {
    if (lock_fd_ >= 0) {
      ::flock(lock_fd_, LOCK_UN);
      ::close(lock_fd_);
      lock_fd_ = -1;
    }
  }
  std::string serial_;
  pid_t pid_ = -1;
  int lock_fd_ = -1;
};

}  // namespace irdist::testing
