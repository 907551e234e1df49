#include "station/serial_transport.h"

#include <gtest/gtest.h>
#include <pty.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace irdist {
namespace {

// A raw pty pair; the test plays the peer on the master side.
struct Pty {
  Pty() {
    char name[256] = {0};
    EXPECT_EQ(openpty(&master, &slave, name, nullptr, nullptr), 0);
    termios tio{};
    tcgetattr(slave, &tio);
    cfmakeraw(&tio);
    tcsetattr(slave, TCSANOW, &tio);
    path = name;
  }
  ~Pty() {
    close(master);
    close(slave);
  }
  Pty(const Pty&) = delete;
  Pty& operator=(const Pty&) = delete;
  void Send(const std::string& s) const { ASSERT_EQ(write(master, s.data(), s.size()), (ssize_t)s.size()); }
  std::string Receive() const {
    char buf[256];
    const ssize_t n = read(master, buf, sizeof(buf));
    return n > 0 ? std::string(buf, static_cast<std::size_t>(n)) : "";
  }
  int master = -1, slave = -1;
  std::string path;
};

TEST(SerialOptions, DefaultsAreValid) {
  std::string why;
  EXPECT_TRUE(SerialOptions{}.IsValid(&why)) << why;
  SerialOptions bad;
  bad.baud = 0;
  EXPECT_FALSE(bad.IsValid(&why));
}

TEST(SerialTransport, WritesCrLfAndReadsLines) {
  Pty pty;
  SerialTransport t(pty.path);
  t.WriteLine("#1 *IDN?*00");
  EXPECT_EQ(pty.Receive(), "#1 *IDN?*00\r\n");
  pty.Send("first\r\nsecond\npart");
  EXPECT_EQ(t.ReadLine(std::chrono::milliseconds(500)), "first");
  EXPECT_EQ(t.ReadLine(std::chrono::milliseconds(500)), "second");
  // "part" has no line end yet: a timeout, and the partial line is kept.
  EXPECT_THROW(t.ReadLine(std::chrono::milliseconds(30)), LinkError);
  pty.Send("ial\n");
  EXPECT_EQ(t.ReadLine(std::chrono::milliseconds(500)), "partial");
}

TEST(SerialTransport, SilentPeerThrowsLinkErrorAfterItsDeadline) {
  Pty pty;
  SerialTransport t(pty.path);
  const auto start = std::chrono::steady_clock::now();
  try {
    t.ReadLine(std::chrono::milliseconds(80));
    FAIL() << "ReadLine returned without a peer";
  } catch (const LinkError& e) {
    EXPECT_NE(std::string(e.what()).find("80 ms"), std::string::npos);
    EXPECT_EQ(e.where(), pty.path);
    EXPECT_FALSE(e.fix().empty());
  }
  // It waited (at least) its deadline and did not block forever: the exception came back.
  EXPECT_GE(std::chrono::steady_clock::now() - start, std::chrono::milliseconds(75));
}

TEST(SerialTransport, FlushDropsPendingBytes) {
  Pty pty;
  SerialTransport t(pty.path);
  pty.Send("stale\n");
  usleep(20000);
  t.Flush();
  pty.Send("fresh\n");
  EXPECT_EQ(t.ReadLine(std::chrono::milliseconds(500)), "fresh");
}

TEST(SerialTransport, LogsEveryLine) {
  Pty pty;
  const std::string path = std::string(IRDIST_BINARY_DIR) + "/serial_transport_test.log";
  {
    LineLog log(path);
    SerialTransport t(pty.path, SerialOptions{}, &log);
    t.WriteLine("#5 POS?*11");
    pty.Receive();
    pty.Send("#5 OK 1,2,3*22\r\n");
    t.ReadLine(std::chrono::milliseconds(500));
  }
  std::ifstream in(path);
  std::stringstream all;
  all << in.rdbuf();
  EXPECT_NE(all.str().find("> #5 POS?*11"), std::string::npos);
  EXPECT_NE(all.str().find("< #5 OK 1,2,3*22"), std::string::npos);
}

TEST(SerialTransport, MissingPortThrowsLinkError) {
  EXPECT_THROW(SerialTransport("/dev/does-not-exist-irdist"), LinkError);
}

// A baud of 0 (station-test --baud 0) is a LinkError naming the port, where the baud was given
// and the fix; it was an internal check. The origin also replaces "check the rig file" when the
// port came from elsewhere.
TEST(SerialTransport, InvalidBaudIsALinkErrorNamingWhereItWasGiven) {
  Pty pty;
  SerialOptions options;
  options.origin = "the PORT and --baud of irdist station-test";
  for (unsigned int baud : {0u, kMaxBaud + 1}) {
    options.baud = baud;
    try {
      SerialTransport transport(pty.path, options);
      ADD_FAILURE() << "baud " << baud << " accepted";
    } catch (const LinkError& e) {
      EXPECT_EQ(e.where(), pty.path);
      EXPECT_NE(e.failure().find("baud must lie in 1..4000000"), std::string::npos) << e.what();
      EXPECT_NE(e.fix().find("fix the PORT and --baud of irdist station-test"), std::string::npos)
          << e.what();
    }
  }
  options.baud = 115200;
  try {
    SerialTransport transport("/dev/does-not-exist-irdist", options);
    ADD_FAILURE() << "a missing port opened";
  } catch (const LinkError& e) {
    EXPECT_EQ(std::string(e.what()).find("rig file"), std::string::npos) << e.what();
    EXPECT_NE(e.fix().find("check the PORT and --baud of irdist station-test"), std::string::npos)
        << e.what();
  }
}


// Regression: two commands on one port both moved the station. The port is held for the
// transport's lifetime (flock and TIOCEXCL); a second opener is refused naming the holder's pid
// and command; once the holder closes, the port opens again and is no longer exclusive.
TEST(SerialTransport, SecondOpenerIsRefusedNamingTheHolder) {
  Pty pty;
  auto exclusive = [&] {
    int flag = -1;
    EXPECT_EQ(ioctl(pty.slave, TIOCGEXCL, &flag), 0);
    return flag;
  };
  {
    SerialTransport first(pty.path);
    EXPECT_EQ(exclusive(), 1);
    try {
      SerialTransport second(pty.path);
      FAIL() << "a second opener of " << pty.path << " was let in";
    } catch (const LinkError& e) {
      const std::string holder = "in use by process " + std::to_string(getpid()) + " (";
      EXPECT_NE(e.failure().find(holder), std::string::npos) << e.what();
      EXPECT_NE(e.failure().find("test_station_serial_transport"), std::string::npos) << e.what();
      EXPECT_EQ(e.where(), pty.path);
      EXPECT_FALSE(e.fix().empty());
    }
    first.WriteLine("still mine");
    EXPECT_EQ(pty.Receive(), "still mine\r\n");
  }
  EXPECT_EQ(exclusive(), 0);  // cleared at close: the emulator's side keeps the tty open
  SerialTransport again(pty.path);
  EXPECT_EQ(exclusive(), 1);
}

// Regression: a rig whose port is /dev/zero or a FIFO said "not found". It says what the
// file is and that a serial device (a character device that is a tty) is needed.
TEST(SerialTransport, NonSerialPortsAreNamedForWhatTheyAre) {
  char dir_template[] = "/tmp/irdist_serial_XXXXXX";
  ASSERT_NE(mkdtemp(dir_template), nullptr);
  const std::string dir = dir_template;
  const std::string fifo = dir + "/fifo", plain = dir + "/plain";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  std::ofstream(plain) << "x";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"/dev/zero", "a character device but not a tty"},
      {"/dev/null", "a character device but not a tty"},
      {fifo, "a FIFO (named pipe), not a serial port"},
      {plain, "a regular file, not a serial port"},
      {dir, "a folder, not a serial port"},
      {dir + "/missing", "no such serial port"}};
  for (const auto& [path, said] : cases) {
    try {
      SerialTransport transport(path);
      ADD_FAILURE() << path << " opened as a serial port";
    } catch (const LinkError& e) {
      EXPECT_NE(e.failure().find(said), std::string::npos) << e.what();
      EXPECT_EQ(e.where(), path);
      if (path != dir + "/missing") {
        EXPECT_NE(e.failure().find("a character device that is a tty"), std::string::npos)
            << e.what();
      }
    }
  }
  unlink(fifo.c_str());
  unlink(plain.c_str());
  rmdir(dir.c_str());
}

}  // namespace
}  // namespace irdist
