// irdist_loopback_netns PROGRAM [ARGS...]: runs a test that starts a GigE Vision camera on
// 127.0.0.1:3956 in a network namespace of its own, whose only interface is loopback (brought up
// here), so that no discovery broadcast of a test ever leaves it (the house rule: GigE traffic on
// loopback only). Where the kernel refuses a namespace (no CAP_SYS_ADMIN), the test runs in the
// host's network and says so; CTest runs the camera tests one at a time either way (their resource
// lock, cmake/IrdistTargets.cmake), so two never share 127.0.0.1:3956.
#include <net/if.h>
#include <sched.h>
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

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) return Fail("usage: irdist_loopback_netns PROGRAM [ARGS...]", nullptr);
  if (unshare(CLONE_NEWNET) == 0) {
    if (!LoopbackUp()) return Fail("cannot bring loopback up in the namespace", std::strerror(errno));
  } else if (errno == EPERM || errno == EINVAL || errno == ENOSYS) {
    std::fprintf(stderr,
                 "irdist_loopback_netns: no network namespace here (%s); the camera test runs on "
                 "the host's loopback\n",
                 std::strerror(errno));
  } else {
    return Fail("unshare(CLONE_NEWNET)", std::strerror(errno));
  }
  execv(argv[1], argv + 1);
  return Fail("cannot run the test", std::strerror(errno));
}
