#pragma once
// Test-only: the host side of an emulated serial device, raw POSIX I/O on the pty's slave, and
// the construction of a device emulator from an inline rig file (no station/ code).

#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <sys/file.h>
#include <sys/ioctl.h>
#include <termios.h>
#include <unistd.h>

#include <chrono>
#include <memory>
#include <string>
#include <thread>

#include "sim/device_emulator.h"
#include "sim/world.h"

namespace irdist::sim::testing {

class PtyHost {
 public:
  explicit PtyHost(const std::string& path) {
    fd_ = ::open(path.c_str(), O_RDWR | O_NOCTTY);
    EXPECT_GE(fd_, 0) << path;
    termios tio{};
    if (fd_ >= 0 && tcgetattr(fd_, &tio) == 0) {
      cfmakeraw(&tio);
      tcsetattr(fd_, TCSANOW, &tio);
    }
  }
  ~PtyHost() {
    if (fd_ >= 0) ::close(fd_);
  }
  PtyHost(const PtyHost&) = delete;
  PtyHost& operator=(const PtyHost&) = delete;

  void Send(const std::string& bytes) {
    ASSERT_EQ(::write(fd_, bytes.data(), bytes.size()), static_cast<ssize_t>(bytes.size()));
  }
  // The next line without its CR LF, or "" after `timeout_ms` of silence.
  std::string ReadLine(int timeout_ms = 3000) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
    while (true) {
      const std::size_t nl = buffer_.find('\n');
      if (nl != std::string::npos) {
        std::string line = buffer_.substr(0, nl);
        buffer_.erase(0, nl + 1);
        if (!line.empty() && line.back() == '\r') line.pop_back();
        return line;
      }
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
                            until - std::chrono::steady_clock::now()).count();
      if (left <= 0) return "";
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, static_cast<int>(left)) > 0) {
        char buf[256];
        const ssize_t n = ::read(fd_, buf, sizeof(buf));
        if (n > 0) buffer_.append(buf, static_cast<std::size_t>(n));
      }
    }
  }
  // Every byte received within `timeout_ms` (line ends included), for replies without an LF.
  std::string ReadRaw(int timeout_ms) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
    while (true) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
                            until - std::chrono::steady_clock::now()).count();
      if (left <= 0) break;
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, static_cast<int>(left)) > 0) {
        char buf[256];
        const ssize_t n = ::read(fd_, buf, sizeof(buf));
        if (n > 0) buffer_.append(buf, static_cast<std::size_t>(n));
      }
    }
    std::string bytes;
    bytes.swap(buffer_);
    return bytes;
  }
  std::string Ask(const std::string& line, int timeout_ms = 3000) {
    Send(line);
    return ReadLine(timeout_ms);
  }

 private:
  int fd_ = -1;
  std::string buffer_;
};

// Builds the emulator of `driver` for device `name` of an inline rig file.
inline std::unique_ptr<DeviceEmulator> MakeEmulator(World& world, const std::string& driver,
                                                    const std::string& name,
                                                    const std::string& rig_text) {
  const EmulatorInfo* info = FindEmulator(driver);
  EXPECT_NE(info, nullptr) << driver;
  if (info == nullptr) return nullptr;
  return info->create(world, EmulatorSpec{name, driver, "inline-rig.yaml", rig_text, 7});
}

// Polls `done` every millisecond for up to `timeout_s` host seconds.
template <typename Done>
bool WaitFor(Done done, double timeout_s = 10.0) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (std::chrono::steady_clock::now() < until) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return done();
}

// The pty's exclusive flag (TIOCEXCL) as a new opener finds it.
inline bool PtyExclusive(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK);  // root passes EBUSY
  int flag = -1;
  EXPECT_GE(fd, 0) << path;
  EXPECT_EQ(::ioctl(fd, TIOCGEXCL, &flag), 0);
  ::close(fd);
  return flag == 1;
}

// Regression: a client killed while it held the pty exclusive (TIOCEXCL, no flock left) must not
// lock every later non-root client out: the emulator clears the flag within a second; while a
// client holds its flock the flag stays.
inline void ExpectAbandonedExclusiveReleased(const std::string& path) {
  const int live = ::open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK);
  ASSERT_GE(live, 0) << path;
  ASSERT_EQ(::flock(live, LOCK_EX | LOCK_NB), 0);
  ASSERT_EQ(::ioctl(live, TIOCEXCL), 0);
  std::this_thread::sleep_for(std::chrono::milliseconds(800));
  EXPECT_TRUE(PtyExclusive(path)) << "cleared under a live client";
  ::close(live);  // killed: the flock goes with the process, the flag stays on the tty
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(2);
  while (PtyExclusive(path) && std::chrono::steady_clock::now() < until) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  EXPECT_FALSE(PtyExclusive(path)) << "the flag of a dead client stays on " << path;
}

}  // namespace irdist::sim::testing
