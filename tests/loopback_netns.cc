// irdist_loopback_netns LOCKFILE PROGRAM [ARGS...]: runs a test that starts a GigE Vision camera on
// 127.0.0.1:3956 in a network namespace of its own, whose only interface is loopback (brought up
// here). Each such test then owns its own 127.0.0.1:3956, and no
// discovery broadcast of a test ever leaves the namespace (the house rule: GigE traffic on loopback
// only). Where the kernel refuses a namespace (no CAP_SYS_ADMIN), the test runs in the host's
// network holding an exclusive flock on LOCKFILE for its whole life (the descriptor survives the
// exec): one camera test at a time, as a CTest resource lock would give, and a note says so once.
#include <fcntl.h>
#include <net/if.h>
#include <sched.h>
#include <sys/file.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace {

int Fail(const char* what, const char* detail) {
  std::fprintf(stderr, "irdist_loopback_netns: %s%s%s\n", what, detail ? ": " : "",
               detail ? detail : "");
  return 127;
}

// Brings the namespace's loopback interface up (a new namespace starts with it down).
bool LoopbackUp() {
  const int fd = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return false;
  ifreq request{};
  std::strncpy(request.ifr_name, "lo", IFNAMSIZ - 1);
  bool ok = ioctl(fd, SIOCGIFFLAGS, &request) == 0;
  if (ok) {
    request.ifr_flags = static_cast<short>(request.ifr_flags | IFF_UP | IFF_RUNNING);
    ok = ioctl(fd, SIOCSIFFLAGS, &request) == 0;
  }
  const int saved = errno;
  close(fd);
  errno = saved;
  return ok;
}

// The fallback: an exclusive lock on `path`, held until the test exits.
bool HoldLock(const char* path) {
  const int fd = open(path, O_RDWR | O_CREAT, 0600);  // no O_CLOEXEC: the test inherits the lock
  if (fd < 0) return false;
  while (flock(fd, LOCK_EX) != 0) {
    if (errno != EINTR) return false;
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) return Fail("usage: irdist_loopback_netns LOCKFILE PROGRAM [ARGS...]", nullptr);
  if (unshare(CLONE_NEWNET) == 0) {
    if (!LoopbackUp()) return Fail("cannot bring loopback up in the namespace", std::strerror(errno));
  } else if (errno == EPERM || errno == EINVAL || errno == ENOSYS) {
    std::fprintf(stderr,
                 "irdist_loopback_netns: no network namespace here (%s); the camera test runs on "
                 "the host's loopback, one at a time (lock %s)\n",
                 std::strerror(errno), argv[1]);
    if (!HoldLock(argv[1])) return Fail("cannot lock", argv[1]);
  } else {
    return Fail("unshare(CLONE_NEWNET)", std::strerror(errno));
  }
  execv(argv[2], argv + 2);
  return Fail("cannot run the test", std::strerror(errno));
}
