// station/port_lock.h: a port held by one process, its holder named from /proc/locks.
#include "station/port_lock.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <pty.h>
#include <sys/file.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <string>

#include "station/transport.h"

namespace irdist {
namespace {

TEST(PortLock, TheHolderOfAnFlockIsNamedWithItsCommand) {
  char path[] = "/tmp/irdist_port_lock_XXXXXX";
  const int fd = mkstemp(path);
  ASSERT_GE(fd, 0);
  EXPECT_EQ(PortLockHolder(path), "");  // nobody holds it
  ASSERT_EQ(flock(fd, LOCK_EX), 0);
  const std::string holder = PortLockHolder(path);
  EXPECT_EQ(holder.rfind("process " + std::to_string(getpid()) + " (", 0), 0u) << holder;
  EXPECT_NE(holder.find("test_station_port_lock"), std::string::npos) << holder;
  close(fd);
  EXPECT_EQ(PortLockHolder(path), "");  // the close let it go
  unlink(path);
}

TEST(PortLock, AnOpenedPortIsExclusiveUntilClosed) {
  int master = -1, slave = -1;
  char name[256] = {};
  ASSERT_EQ(openpty(&master, &slave, name, nullptr, nullptr), 0);
  const int fd = OpenExclusivePort(name, "the test's pty");
  int exclusive = 0;
  ASSERT_EQ(ioctl(slave, TIOCGEXCL, &exclusive), 0);
  EXPECT_EQ(exclusive, 1);
  EXPECT_THROW(OpenExclusivePort(name, "the test's pty"), LinkError);
  CloseExclusivePort(fd);
  ASSERT_EQ(ioctl(slave, TIOCGEXCL, &exclusive), 0);
  EXPECT_EQ(exclusive, 0);
  CloseExclusivePort(OpenExclusivePort(name, "the test's pty"));  // free again
  close(master);
  close(slave);
}

}  // namespace
}  // namespace irdist
