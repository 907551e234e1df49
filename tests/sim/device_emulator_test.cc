#include "sim/device_emulator.h"

#include <fcntl.h>
#include <stdlib.h>
#include <sys/file.h>
#include <sys/ioctl.h>
#include <unistd.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <thread>

// What every device emulator shares (sim/device_emulator.h): the fault knobs' checks, the
// registry of emulators by driver name, and the release of a pty left exclusive by a dead client.

namespace irdist::sim {
namespace {

TEST(EmulatorFaults, DefaultsAndTheEndsOfEachRangeAreValid) {
  std::string why;
  EXPECT_TRUE(EmulatorFaults{}.IsValid(&why)) << why;
  EmulatorFaults edges;
  edges.garble_rate = 1.0;
  edges.drop_rate = 1.0;
  edges.delay_rate = 0.0;
  edges.delay_s = 0.0;
  edges.power_cycle_after_s = 0.0;
  edges.stuck_axis = "tilt";
  EXPECT_TRUE(edges.IsValid(&why)) << why;
  EXPECT_TRUE(edges.IsValid(nullptr));
}

// Each knob out of its range is refused with a reason naming that knob.
TEST(EmulatorFaults, EachKnobOutOfRangeIsRefusedNamingIt) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  struct Case {
    const char* knob;
    void (*set)(EmulatorFaults&, double);
    double value;
  };
  const Case cases[] = {
      {"garble_rate", [](EmulatorFaults& f, double v) { f.garble_rate = v; }, 1.01},
      {"garble_rate", [](EmulatorFaults& f, double v) { f.garble_rate = v; }, nan},
      {"drop_rate", [](EmulatorFaults& f, double v) { f.drop_rate = v; }, -0.01},
      {"delay_rate", [](EmulatorFaults& f, double v) { f.delay_rate = v; }, 2.0},
      {"delay_s", [](EmulatorFaults& f, double v) { f.delay_s = v; }, -0.5},
      {"delay_s", [](EmulatorFaults& f, double v) { f.delay_s = v; }, inf},
      {"power_cycle_after_s", [](EmulatorFaults& f, double v) { f.power_cycle_after_s = v; }, inf},
      {"power_cycle_after_s", [](EmulatorFaults& f, double v) { f.power_cycle_after_s = v; }, nan},
  };
  for (const Case& c : cases) {
    EmulatorFaults faults;
    c.set(faults, c.value);
    std::string why;
    EXPECT_FALSE(faults.IsValid(&why)) << c.knob << " = " << c.value;
    EXPECT_NE(why.find(c.knob), std::string::npos) << why;
    EXPECT_FALSE(faults.IsValid(nullptr));
  }
  EmulatorFaults roll;
  roll.stuck_axis = "roll";
  std::string why;
  EXPECT_FALSE(roll.IsValid(&why));
  EXPECT_NE(why.find("stuck_axis"), std::string::npos) << why;
}

// The three vendor device kinds of the virtual rig register themselves under their drivers'
// names; the irdist station's emulator is StationEmulator, not in this registry.
TEST(FindEmulator, FindsEachRegisteredDeviceKindByItsDriverName) {
  for (const char* driver : {"zaber_ascii", "flir_ptu", "scpi_source"}) {
    const EmulatorInfo* info = FindEmulator(driver);
    ASSERT_NE(info, nullptr) << driver;
    EXPECT_EQ(info->driver, driver);
    EXPECT_TRUE(static_cast<bool>(info->create)) << driver;
  }
  EXPECT_EQ(FindEmulator("irdist_station"), nullptr);
  EXPECT_EQ(FindEmulator("Zaber_ASCII"), nullptr);
  EXPECT_EQ(FindEmulator(""), nullptr);
}

IRDIST_REGISTER_EMULATOR(test_kind, (EmulatorInfo{"test_kind", nullptr}));

TEST(FindEmulator, ARegistrationMakesItsDriverFindable) {
  const EmulatorInfo* info = FindEmulator("test_kind");
  ASSERT_NE(info, nullptr);
  EXPECT_EQ(info->driver, "test_kind");
  EXPECT_NE(FindEmulator("zaber_ascii"), info);
}

// A pseudo-terminal as the emulators hold it: the master, and the slave the clients open.
class Pty {
 public:
  Pty() {
    master_ = ::posix_openpt(O_RDWR | O_NOCTTY);
    EXPECT_GE(master_, 0);
    EXPECT_EQ(::grantpt(master_), 0);
    EXPECT_EQ(::unlockpt(master_), 0);
    path_ = ::ptsname(master_);
    slave_ = ::open(path_.c_str(), O_RDWR | O_NOCTTY);
    EXPECT_GE(slave_, 0) << path_;
  }
  ~Pty() {
    if (slave_ >= 0) {
      ::ioctl(slave_, TIOCNXCL);
      ::close(slave_);
    }
    if (master_ >= 0) ::close(master_);
  }
  Pty(const Pty&) = delete;
  Pty& operator=(const Pty&) = delete;

  int slave() const { return slave_; }
  const std::string& path() const { return path_; }
  bool Exclusive() const {
    int flag = -1;
    EXPECT_EQ(::ioctl(slave_, TIOCGEXCL, &flag), 0);
    return flag == 1;
  }

 private:
  int master_ = -1, slave_ = -1;
  std::string path_;
};

// A client that set TIOCEXCL and died (its flock gone with it) leaves the flag: it is cleared.
TEST(ReleaseAbandonedExclusive, ClearsTheFlagOfAClientThatHoldsNoFlock) {
  Pty pty;
  ASSERT_EQ(::ioctl(pty.slave(), TIOCEXCL), 0);
  ASSERT_TRUE(pty.Exclusive());
  EXPECT_TRUE(ReleaseAbandonedExclusive(pty.slave()));
  EXPECT_FALSE(pty.Exclusive());
  // Nothing to clear: not exclusive.
  EXPECT_FALSE(ReleaseAbandonedExclusive(pty.slave()));
  EXPECT_FALSE(pty.Exclusive());
}

// A live client (its flock held, as irdist's serial transport holds it) keeps its flag.
TEST(ReleaseAbandonedExclusive, LeavesTheFlagOfALiveClientHoldingItsFlock) {
  Pty pty;
  const int client = ::open(pty.path().c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK);
  ASSERT_GE(client, 0);
  ASSERT_EQ(::flock(client, LOCK_EX | LOCK_NB), 0);
  ASSERT_EQ(::ioctl(client, TIOCEXCL), 0);
  EXPECT_FALSE(ReleaseAbandonedExclusive(pty.slave()));
  EXPECT_TRUE(pty.Exclusive());
  ::close(client);  // the client dies: its flock goes, the flag stays
  EXPECT_TRUE(pty.Exclusive());
  EXPECT_TRUE(ReleaseAbandonedExclusive(pty.slave()));
  EXPECT_FALSE(pty.Exclusive());
}

TEST(ReleaseAbandonedExclusive, AnInvalidDescriptorIsLeftAlone) {
  EXPECT_FALSE(ReleaseAbandonedExclusive(-1));
}

// The watch clears at once, then looks again only after a quarter of a second.
TEST(AbandonedExclusiveWatch, ChecksAtMostEveryQuarterSecond) {
  Pty pty;
  AbandonedExclusiveWatch watch;
  ASSERT_EQ(::ioctl(pty.slave(), TIOCEXCL), 0);
  watch.Poll(pty.slave());
  EXPECT_FALSE(pty.Exclusive()) << "the first poll did not look";
  ASSERT_EQ(::ioctl(pty.slave(), TIOCEXCL), 0);
  watch.Poll(pty.slave());
  EXPECT_TRUE(pty.Exclusive()) << "looked again within 250 ms";
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  watch.Poll(pty.slave());
  EXPECT_FALSE(pty.Exclusive()) << "did not look again after 300 ms";
}

}  // namespace
}  // namespace irdist::sim
