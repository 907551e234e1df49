#include "sim/station_emulator.h"

#include "base/input_error.h"
#include "tests/sim/pty_host.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <thread>

namespace irdist::sim {
namespace {

std::uint8_t Crc8(const std::string& text) {
  std::uint8_t crc = 0;
  for (unsigned char c : text) {
    crc ^= c;
    for (int i = 0; i < 8; ++i) crc = (crc & 0x80) ? ((crc << 1) ^ 0x07) : (crc << 1);
  }
  return crc;
}

std::string Frame(int seq, const std::string& command) {
  const std::string text = "#" + std::to_string(seq) + " " + command;
  char cs[4];
  std::snprintf(cs, sizeof(cs), "%02X", Crc8(text));
  return text + "*" + cs;
}

// A minimal host written from the protocol document: raw POSIX I/O on the pty's slave side.
class Host {
 public:
  explicit Host(const std::string& path) {
    fd_ = open(path.c_str(), O_RDWR | O_NOCTTY);
    EXPECT_GE(fd_, 0) << path;
    termios tio{};
    tcgetattr(fd_, &tio);
    cfmakeraw(&tio);
    tcsetattr(fd_, TCSANOW, &tio);
  }
  ~Host() { close(fd_); }
  Host(const Host&) = delete;
  Host& operator=(const Host&) = delete;

  void SendRaw(const std::string& line) {
    const std::string bytes = line + "\r\n";
    ASSERT_EQ(write(fd_, bytes.data(), bytes.size()), static_cast<ssize_t>(bytes.size()));
  }
  // Next line (without CR LF), or "" after `timeout_ms` of silence.
  std::string ReadLine(int timeout_ms = 500) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
    while (true) {
      const std::size_t nl = buffer_.find('\n');
      if (nl != std::string::npos) {
        std::string line = buffer_.substr(0, nl);
        buffer_.erase(0, nl + 1);
        if (!line.empty() && line.back() == '\r') line.pop_back();
        return line;
      }
      const int left = static_cast<int>(std::chrono::duration_cast<std::chrono::milliseconds>(
                                            until - std::chrono::steady_clock::now())
                                            .count());
      if (left <= 0) return "";
      pollfd p{fd_, POLLIN, 0};
      if (poll(&p, 1, left) > 0) {
        char buf[256];
        const ssize_t n = read(fd_, buf, sizeof(buf));
        if (n > 0) buffer_.append(buf, static_cast<std::size_t>(n));
      }
    }
  }
  // Sends a command and returns the reply body ("OK ..." / "ERR ...") after checking its frame.
  std::string Ask(const std::string& command) {
    seq_ = (seq_ + 1) % 10000;  // sequence numbers wrap at 9999
    const int seq = seq_;
    SendRaw(Frame(seq, command));
    const std::string line = ReadLine();
    EXPECT_GE(line.size(), 4u) << command;
    if (line.size() < 4) return "";
    const std::size_t star = line.rfind('*');
    EXPECT_EQ(star, line.size() - 3) << line;
    char cs[4];
    std::snprintf(cs, sizeof(cs), "%02X", Crc8(line.substr(0, star)));
    EXPECT_EQ(line.substr(star + 1), cs) << line;
    const std::string prefix = "#" + std::to_string(seq) + " ";
    EXPECT_EQ(line.substr(0, prefix.size()), prefix) << line;
    return line.substr(prefix.size(), star - prefix.size());
  }
  std::string WaitState(const std::string& wanted, const World& world, double max_sim_s,
                        const std::string& or_state = "") {
    const double t0 = world.clock().Now();
    std::string state;
    while (world.clock().Now() - t0 < max_sim_s) {
      state = Ask("STAT?");
      if (state.rfind("OK " + wanted + ",", 0) == 0) return wanted;
      if (!or_state.empty() && state.rfind("OK " + or_state + ",", 0) == 0) return or_state;
      std::this_thread::sleep_for(std::chrono::microseconds(500));
    }
    return state;
  }
  int seq_ = 0;

 private:
  int fd_ = -1;
  std::string buffer_;
};

double Trapezoid(double d, double v, double a) {
  return d >= v * v / a ? d / v + v / a : 2.0 * std::sqrt(d / a);
}

TEST(EmulatorOptions, DefaultsAreValid) {
  std::string why;
  EXPECT_TRUE(EmulatorOptions{}.IsValid(&why)) << why;
  EmulatorOptions bad;
  bad.garble_rate = 1.5;
  EXPECT_FALSE(bad.IsValid(&why));
  bad = EmulatorOptions{};
  bad.stuck_axis = "roll";
  EXPECT_FALSE(bad.IsValid(&why));
  bad = EmulatorOptions{};
  bad.pan.home = 90.0;
  EXPECT_FALSE(bad.IsValid(&why));
}

TEST(EmulatorOptions, LoadsTheVirtualRigFile) {
  const EmulatorOptions o =
      LoadEmulatorOptions(std::string(IRDIST_SOURCE_DIR) + "/recipes/rigs/virtual.yaml");
  std::string why;
  EXPECT_TRUE(o.IsValid(&why)) << why;
  EXPECT_DOUBLE_EQ(o.slide.min, 1000.0);  // from station.limits
  EXPECT_DOUBLE_EQ(o.slide.max, 3500.0);
  EXPECT_DOUBLE_EQ(o.pan.max, 45.0);
  EXPECT_DOUBLE_EQ(o.max_current_ma, 600.0);
}

TEST(EmulatorOptions, ReadsFaultsAndRejectsBadValues) {
  const std::string path = std::string(IRDIST_BINARY_DIR) + "/station_emulator_test_rig.yaml";
  {
    std::ofstream out(path);
    out << "virtual:\n  station:\n    drop_rate: 0.25\n    stuck_axis: tilt\n"
           "    slide: {speed: 123, accel: 456}\n";
  }
  const EmulatorOptions o = LoadEmulatorOptions(path);
  EXPECT_DOUBLE_EQ(o.drop_rate, 0.25);
  EXPECT_EQ(o.stuck_axis, "tilt");
  EXPECT_DOUBLE_EQ(o.slide.speed, 123.0);
  EXPECT_DOUBLE_EQ(o.slide.accel, 456.0);
  {
    std::ofstream out(path);
    out << "virtual:\n  station:\n    drop_rate: lots\n";
  }
  EXPECT_THROW(LoadEmulatorOptions(path), Error);
  {
    std::ofstream out(path);
    out << "virtual:\n  station:\n    drop_rate: 2\n";
  }
  EXPECT_THROW(LoadEmulatorOptions(path), Error);
}

// A misspelt key under virtual.station: is an InputError naming file:line, never ignored (a fault
// a test thinks it injects must be injected).
TEST(EmulatorOptions, AMisspeltKeyIsAnInputErrorWithItsLine) {
  const std::string path = std::string(IRDIST_BINARY_DIR) + "/station_emulator_test_typo.yaml";
  {
    std::ofstream out(path);
    out << "virtual:\n  station:\n    drop_rate: 0.1\n    reboot_afer_s: 3\n";
  }
  try {
    LoadEmulatorOptions(path);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.Line(), 4) << e.what();
    EXPECT_NE(e.Message().find("reboot_after_s"), std::string::npos) << e.what();
  }
  {
    std::ofstream out(path);
    out << "virtual:\n  station:\n    slide: {sped: 100}\n";
  }
  EXPECT_THROW(LoadEmulatorOptions(path), InputError);
}

TEST(StationEmulator, PowersUpUnhomedIredOffWithABootId) {
  World world(50.0);
  StationEmulator emulator(world, EmulatorOptions{});
  Host host(emulator.Start());
  const std::string idn = host.Ask("*IDN?");
  ASSERT_EQ(idn.rfind("OK IRDIST,", 0), 0u) << idn;
  const std::string boot = idn.substr(idn.rfind(',') + 1);
  EXPECT_EQ(boot, emulator.BootId());
  EXPECT_EQ(boot.size(), 8u);
  EXPECT_EQ(host.Ask("STAT?"), "OK UNHOMED," + boot);
  EXPECT_EQ(host.Ask("SOUR:CURR?"), "OK 0");
  EXPECT_EQ(host.Ask("SYST:ERR?"), "OK -500,\"Power on\"");
  EXPECT_EQ(host.Ask("SYST:ERR?"), "OK 0,\"No error\"");
  EXPECT_EQ(host.Ask("MOVE 200000,0,0"), "ERR 201,\"Not homed\"");
  EXPECT_EQ(world.Pose().bias_ma, 0.0);
}

TEST(StationEmulator, AnExclusiveFlagLeftByADeadClientIsCleared) {
  World world(50.0);
  StationEmulator emulator(world, EmulatorOptions{});
  testing::ExpectAbandonedExclusiveReleased(emulator.Start());
}

TEST(StationEmulator, HomesAndMovesInTheTimeTheProfileSays) {
  World world(20.0);
  const EmulatorOptions o;
  StationEmulator emulator(world, o);
  Host host(emulator.Start());
  EXPECT_EQ(host.Ask("HOME"), "OK");
  EXPECT_EQ(host.WaitState("IDLE", world, 60.0), "IDLE");
  EXPECT_EQ(host.Ask("POS?"), "OK 100000,0,0");
  // 1000 -> 2800 mm on the slide and 0 -> 30 deg on pan at once: the slower axis sets the time.
  const double expected = std::max(Trapezoid(1800.0, o.slide.speed, o.slide.accel),
                                   Trapezoid(30.0, o.pan.speed, o.pan.accel));
  const double t0 = world.clock().Now();
  EXPECT_EQ(host.Ask("MOVE 280000,3000,0"), "OK");
  EXPECT_EQ(host.Ask("STAT?").substr(0, 9), "OK MOVING");
  EXPECT_TRUE(world.Pose().moving);
  // The profile's end: SETTLING, or IDLE where a loaded host's polls missed the settling window
  // (time scale 20: the settle is a few ms of wall time); either way not before the profile.
  const std::string ended = host.WaitState("SETTLING", world, 60.0, "IDLE");
  EXPECT_TRUE(ended == "SETTLING" || ended == "IDLE") << ended;
  const double profile_end = world.clock().Now() - t0;
  EXPECT_EQ(host.WaitState("IDLE", world, 60.0), "IDLE");
  const double idle = world.clock().Now() - t0;
  EXPECT_GE(profile_end, expected - 0.01);
  EXPECT_GE(idle, expected + o.slide.settle_s - 0.01);
  EXPECT_EQ(host.Ask("POS?"), "OK 280000,3000,0");
  EXPECT_FALSE(world.Pose().moving);
  EXPECT_NEAR(world.Pose().slide_mm, 2800.0, 1e-9);
  EXPECT_NEAR(world.Pose().pan_deg, 30.0, 1e-9);
}

TEST(StationEmulator, SoftLimitsAndBadCommandsQueueErrors) {
  World world(50.0);
  StationEmulator emulator(world, EmulatorOptions{});
  Host host(emulator.Start());
  host.Ask("*CLS");
  host.Ask("HOME");
  host.WaitState("IDLE", world, 60.0);
  EXPECT_EQ(host.Ask("MOVE 360000,0,0"), "ERR -222,\"Data out of range\"");
  EXPECT_EQ(host.Ask("LIM TILT,-1000,1000"), "OK");
  EXPECT_EQ(host.Ask("LIM?"), "OK 100000,350000,-4500,4500,-1000,1000");
  EXPECT_EQ(host.Ask("MOVE 200000,0,1001"), "ERR -222,\"Data out of range\"");
  EXPECT_EQ(host.Ask("LIM TILT,-9000,1000"), "ERR -222,\"Data out of range\"");
  EXPECT_EQ(host.Ask("MOVE 200000,0"), "ERR -109,\"Missing parameter\"");
  EXPECT_EQ(host.Ask("MOVE 200000,0,1.5"), "ERR -104,\"Data type error\"");
  EXPECT_EQ(host.Ask("WARP 9"), "ERR -113,\"Undefined header\"");
  EXPECT_EQ(host.Ask("SYST:ERR?"), "OK -222,\"Data out of range\"");
  for (int i = 0; i < 5; ++i) host.Ask("SYST:ERR?");
  EXPECT_EQ(host.Ask("SYST:ERR?"), "OK 0,\"No error\"");
  EXPECT_EQ(host.Ask("POS?"), "OK 100000,0,0");
}

TEST(StationEmulator, RetransmissionIsAnsweredNotReexecuted) {
  World world(50.0);
  StationEmulator emulator(world, EmulatorOptions{});
  Host host(emulator.Start());
  host.Ask("TRIG:COUN 3");
  host.Ask("TRIG:PER 1000");
  const std::string fire = Frame(++host.seq_, "TRIG:FIRE");
  host.SendRaw(fire);
  const std::string first = host.ReadLine();
  host.SendRaw(fire);  // the host lost the reply and sends the same line again
  EXPECT_EQ(host.ReadLine(), first);
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_EQ(host.Ask("TRIG:PULS?"), "OK 3,0");
  EXPECT_EQ(world.TriggerPulses(), 3u);
}

TEST(StationEmulator, DamagedRequestIsIgnoredAndQueued) {
  World world(50.0);
  StationEmulator emulator(world, EmulatorOptions{});
  Host host(emulator.Start());
  host.Ask("*CLS");
  std::string bad = Frame(50, "HOME");
  bad[4] = 'X';  // "HOME" -> "HOXE", checksum no longer matches
  host.SendRaw(bad);
  EXPECT_EQ(host.ReadLine(100), "");  // silence
  host.SendRaw("no frame at all");
  EXPECT_EQ(host.ReadLine(100), "");
  EXPECT_EQ(host.Ask("STAT?").substr(0, 10), "OK UNHOMED");
  EXPECT_EQ(host.Ask("SYST:ERR?"), "OK 203,\"Checksum mismatch\"");
  EXPECT_EQ(host.Ask("SYST:ERR?"), "OK -102,\"Syntax error\"");
}

TEST(StationEmulator, RebootMidMoveLosesHomingCurrentAndBootId) {
  World world(50.0);
  StationEmulator emulator(world, EmulatorOptions{});
  Host host(emulator.Start());
  host.Ask("HOME");
  host.WaitState("IDLE", world, 60.0);
  host.Ask("SOUR:CURR 50000");
  EXPECT_DOUBLE_EQ(world.Pose().bias_ma, 500.0);
  const std::string boot = emulator.BootId();
  emulator.RebootDuringNextMove(2.0);
  host.Ask("MOVE 300000,0,0");
  std::this_thread::sleep_for(std::chrono::milliseconds(200));  // 10 s simulated
  std::string stat;
  for (int i = 0; i < 20 && stat.empty(); ++i) stat = host.Ask("STAT?");  // deaf while booting
  EXPECT_EQ(emulator.Reboots(), 1u);
  EXPECT_NE(emulator.BootId(), boot);
  EXPECT_EQ(host.Ask("STAT?"), "OK UNHOMED," + emulator.BootId());
  EXPECT_DOUBLE_EQ(world.Pose().bias_ma, 0.0);
  const double slide = world.Pose().slide_mm;
  EXPECT_GT(slide, 1000.0);  // it stopped where power was lost, part way
  EXPECT_LT(slide, 3000.0);
  EXPECT_FALSE(world.Pose().moving);
}

TEST(StationEmulator, TriggerPulsesAtItsPeriodInSimulatedTime) {
  World world(20.0);
  StationEmulator emulator(world, EmulatorOptions{});
  std::vector<double> t;
  std::mutex m;
  world.SetTriggerSink([&] {
    std::lock_guard<std::mutex> lock(m);
    t.push_back(world.clock().Now());
  });
  Host host(emulator.Start());
  EXPECT_EQ(host.Ask("TRIG:WIDT 500"), "OK");
  EXPECT_EQ(host.Ask("TRIG:PER 400"), "ERR -222,\"Data out of range\"");  // width >= period
  EXPECT_EQ(host.Ask("TRIG:PER 20000"), "OK");
  EXPECT_EQ(host.Ask("TRIG:COUN 4"), "OK");
  EXPECT_EQ(host.Ask("TRIG?"), "OK 4,500,20000");
  EXPECT_EQ(host.Ask("TRIG:FIRE"), "OK");
  std::this_thread::sleep_for(std::chrono::milliseconds(40));  // 0.8 s simulated
  EXPECT_EQ(host.Ask("TRIG:PULS?"), "OK 4,0");
  world.SetTriggerSink(nullptr);
  std::lock_guard<std::mutex> lock(m);
  ASSERT_EQ(t.size(), 4u);
  // Pulses are due every 20 ms simulated; each one leaves late by at most the loop's latency.
  EXPECT_GE(t.back() - t.front(), 3 * 0.020 - 0.005);
  for (std::size_t i = 1; i < t.size(); ++i) EXPECT_GT(t[i] - t[i - 1], 0.010);
}

TEST(StationEmulator, GarbledAndDroppedRepliesAtTheirRates) {
  World world(50.0);
  EmulatorOptions o;
  o.drop_rate = 0.2;
  StationEmulator emulator(world, o);
  Host host(emulator.Start());
  int silent = 0;
  for (int i = 0; i < 100; ++i) {
    host.SendRaw(Frame(++host.seq_, "POS?"));
    if (host.ReadLine(60).empty()) ++silent;
  }
  EXPECT_EQ(static_cast<std::uint64_t>(silent), emulator.RepliesDropped());
  EXPECT_GT(silent, 8);
  EXPECT_LT(silent, 35);
  emulator.SetDropRate(0.0);
  emulator.SetGarbleRate(0.05);
  int damaged = 0;
  for (int i = 0; i < 100; ++i) {
    const std::string expected_prefix = "#" + std::to_string(++host.seq_) + " OK ";
    host.SendRaw(Frame(host.seq_, "POS?"));
    std::string line = host.ReadLine(60);
    const std::size_t star = line.rfind('*');
    char cs[4] = "";
    if (star != std::string::npos) std::snprintf(cs, sizeof(cs), "%02X", Crc8(line.substr(0, star)));
    if (star == std::string::npos || line.substr(star + 1) != cs) ++damaged;
    while (!host.ReadLine(5).empty()) {
    }  // a garbled line end merges lines: drain
  }
  EXPECT_GT(damaged, 30);  // ~25 bytes per reply at 5 % each
  EXPECT_LT(damaged, 95);
}

TEST(StationEmulator, StuckAxisDoesNotMove) {
  World world(50.0);
  StationEmulator emulator(world, EmulatorOptions{});
  Host host(emulator.Start());
  host.Ask("HOME");
  host.WaitState("IDLE", world, 60.0);
  emulator.SetStuckAxis("pan");
  host.Ask("MOVE 120000,1000,500");
  host.WaitState("IDLE", world, 60.0);
  EXPECT_EQ(host.Ask("POS?"), "OK 120000,0,500");
}

}  // namespace
}  // namespace irdist::sim
