#include "station/port_lock.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <termios.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>

#include "station/transport.h"

namespace irdist {
namespace {

constexpr std::size_t kMaxCommandChars = 160;  // of a holder's command line, in a message

const char* KindOf(mode_t mode) {
  if (S_ISFIFO(mode)) return "a FIFO (named pipe)";
  if (S_ISDIR(mode)) return "a folder";
  if (S_ISREG(mode)) return "a regular file";
  if (S_ISSOCK(mode)) return "a socket";
  if (S_ISBLK(mode)) return "a block device";
  return "not a device";
}

const char kSerialNeeded[] =
    "a serial device (a character device that is a tty, e.g. /dev/ttyUSB0 or "
    "/dev/serial/by-id/...) is needed";

// "process 1234 (irdist station move 10)": a live process's command line (control characters
// shown as '?', never sent to a terminal), or its pid alone.
std::string ProcessText(long pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/cmdline", std::ios::binary);
  std::string command((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  while (!command.empty() && command.back() == '\0') command.pop_back();
  for (char& c : command) {
    if (c == '\0') {
      c = ' ';
    } else if (std::iscntrl(static_cast<unsigned char>(c))) {
      c = '?';
    }
  }
  if (command.size() > kMaxCommandChars) command = command.substr(0, kMaxCommandChars) + "...";
  return "process " + std::to_string(pid) + (command.empty() ? "" : " (" + command + ")");
}

[[noreturn]] void InUse(const std::string& path, const std::string& holder,
                        const std::string& origin) {
  throw LinkError("serial port in use by " + (holder.empty() ? "another program" : holder) +
                      "; a port is one command's at a time",
                  path,
                  "end that command (or wait until it ends), or check " + origin +
                      " if this is not the port you meant");
}

// The file must exist and be a character device; anything else is named for what it is.
void CheckIsCharacterDevice(const std::string& path, const std::string& origin) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    const int error = errno;
    throw LinkError(error == ENOENT ? "no such serial port"
                                    : "cannot reach serial port: " + std::string(std::strerror(error)),
                    path,
                    "check " + origin + ", that the device is plugged in (ls -l /dev/serial/by-id) "
                    "and that you may open it (group dialout)");
  }
  if (!S_ISCHR(st.st_mode)) {
    throw LinkError(std::string("this is ") + KindOf(st.st_mode) + ", not a serial port; " +
                        kSerialNeeded,
                    path, "fix " + origin);
  }
}

// Takes flock and TIOCEXCL on the open descriptor; closes it and throws if either fails.
void LockOpenPort(int fd, const std::string& path, const std::string& origin) {
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    const int error = errno;
    ::close(fd);
    if (error == EWOULDBLOCK) InUse(path, PortLockHolder(path), origin);
    throw LinkError("cannot lock serial port: " + std::string(std::strerror(error)), path,
                    "check " + origin);
  }
  if (::ioctl(fd, TIOCEXCL) != 0) {
    const int error = errno;
    ::close(fd);
    throw LinkError("cannot make serial port exclusive (TIOCEXCL): " +
                        std::string(std::strerror(error)),
                    path, "check " + origin + " names a serial device");
  }
}

}  // namespace

std::string PortLockHolder(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return "";
  char wanted[64];
  std::snprintf(wanted, sizeof(wanted), "%02x:%02x:%lu", major(st.st_dev), minor(st.st_dev),
                static_cast<unsigned long>(st.st_ino));
  std::ifstream locks("/proc/locks");
  for (std::string line; std::getline(locks, line);) {
    // "1: FLOCK  ADVISORY  WRITE 1234 00:05:3 0 EOF"; a waiter's line carries "->".
    std::istringstream fields(line);
    std::string number, type, mode, access, pid, file;
    if (!(fields >> number >> type >> mode >> access >> pid >> file)) continue;
    if (type != "FLOCK" || file != wanted) continue;
    char* end = nullptr;
    const long holder = std::strtol(pid.c_str(), &end, 10);
    if (end != pid.c_str() && *end == '\0' && holder > 0) return ProcessText(holder);
  }
  return "";
}

int OpenExclusivePort(const std::string& path, const std::string& origin) {
  CheckIsCharacterDevice(path, origin);
  const int fd = ::open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    const int error = errno;
    // EBUSY: another process set TIOCEXCL on the tty.
    if (error == EBUSY) InUse(path, PortLockHolder(path), origin);
    throw LinkError("cannot open serial port: " + std::string(std::strerror(error)), path,
                    "check " + origin + ", that the device exists and that you may open it "
                    "(group dialout)");
  }
  if (!::isatty(fd)) {
    ::close(fd);
    throw LinkError(std::string("this is a character device but not a tty (a terminal line), "
                                "so not a serial port; ") + kSerialNeeded,
                    path, "fix " + origin);
  }
  LockOpenPort(fd, path, origin);
  return fd;
}

void CloseExclusivePort(int fd) noexcept {
  if (fd < 0) return;
  ::ioctl(fd, TIOCNXCL);  // best effort: the port is being let go
  ::close(fd);
}

}  // namespace irdist
