#pragma once
// Test helper shared by every test that starts a GigE Vision camera on 127.0.0.1 (the virtual
// rig, Aravis's arv-fake-gv-camera-0.8, or the irdist binary running one): only one camera can own
// UDP 127.0.0.1:3956. Within one ctest run the tests hold the CTest lock IRDIST_GVCP_LOCK; across
// build trees they take an exclusive flock on /tmp/irdist-gvcp-127.0.0.1.lock (the project's
// convention for "I own the loopback GVCP port") and wait until the port is really free. The lock
// file is opened without following a link and must be a regular file: a link or FIFO planted
// under that name in the shared /tmp is refused, never followed.

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <sys/file.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <stdexcept>
#include <string>
#include <thread>

namespace irdist::testing {

inline constexpr char kLoopbackGvcpLockPath[] = "/tmp/irdist-gvcp-127.0.0.1.lock";

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

// Waits up to `limit` for UDP 127.0.0.1:3956 to be free; returns whether it is.
inline bool WaitForLoopbackGvcpPort(std::chrono::seconds limit) {
  const auto deadline = std::chrono::steady_clock::now() + limit;
  while (!LoopbackGvcpPortFree()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return true;
}

// Holds the loopback-GVCP flock and has waited until the port is free.
class LoopbackGvcpLock {
 public:
  explicit LoopbackGvcpLock(const std::string& path = kLoopbackGvcpLockPath) {
    fd_ = ::open(path.c_str(), O_CREAT | O_RDWR | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK, 0666);
    std::string reason;
    struct stat st {};
    if (fd_ < 0) {
      reason = std::strerror(errno);
    } else if (::fstat(fd_, &st) != 0 || !S_ISREG(st.st_mode)) {
      reason = "not a regular file";
    } else if (::flock(fd_, LOCK_EX) != 0) {
      reason = std::strerror(errno);
    }
    if (!reason.empty()) {
      Release();
      throw std::runtime_error("cannot lock " + path + " (" + reason +
                               "; a symbolic link or other file planted there is never "
                               "followed): remove it");
    }
    if (!WaitForLoopbackGvcpPort(std::chrono::seconds(60))) {
      Release();
      throw std::runtime_error("UDP 127.0.0.1:3956 stays busy: another camera is running");
    }
  }
  ~LoopbackGvcpLock() { Release(); }
  LoopbackGvcpLock(const LoopbackGvcpLock&) = delete;
  LoopbackGvcpLock& operator=(const LoopbackGvcpLock&) = delete;
  LoopbackGvcpLock(LoopbackGvcpLock&&) = delete;
  LoopbackGvcpLock& operator=(LoopbackGvcpLock&&) = delete;

  void Release() {
    if (fd_ >= 0) ::close(fd_);  // closing releases the flock
    fd_ = -1;
  }

 private:
  int fd_ = -1;
};

}  // namespace irdist::testing
