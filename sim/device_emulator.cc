#include "sim/device_emulator.h"

#include <sys/ioctl.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>

namespace irdist::sim {
namespace {

std::map<std::string, EmulatorInfo>& Registry() {
  static std::map<std::string, EmulatorInfo> emulators;
  return emulators;
}

bool Probability(double p) { return std::isfinite(p) && p >= 0.0 && p <= 1.0; }

}  // namespace

bool EmulatorFaults::IsValid(std::string* why) const {
  const auto fail = [why](const char* text) {
    if (why) *why = text;
    return false;
  };
  if (!Probability(garble_rate)) return fail("garble_rate must be in [0, 1]");
  if (!Probability(drop_rate)) return fail("drop_rate must be in [0, 1]");
  if (!Probability(delay_rate)) return fail("delay_rate must be in [0, 1]");
  if (!std::isfinite(delay_s) || delay_s < 0.0) return fail("delay_s must be >= 0");
  if (!std::isfinite(power_cycle_after_s)) return fail("power_cycle_after_s must be finite");
  if (!stuck_axis.empty() && stuck_axis != "slide" && stuck_axis != "pan" && stuck_axis != "tilt")
    return fail("stuck_axis must be slide, pan, tilt or empty");
  return true;
}

EmulatorRegistration::EmulatorRegistration(EmulatorInfo info) {
  const std::string driver = info.driver;
  Registry()[driver] = std::move(info);
}

const EmulatorInfo* FindEmulator(const std::string& driver) {
  const auto it = Registry().find(driver);
  return it == Registry().end() ? nullptr : &it->second;
}

bool ReleaseAbandonedExclusive(int slave_fd) {
  int exclusive = 0;
  struct stat st {};
  if (::ioctl(slave_fd, TIOCGEXCL, &exclusive) != 0 || exclusive == 0) return false;
  if (::fstat(slave_fd, &st) != 0) return false;
  char file[64];
  std::snprintf(file, sizeof(file), "%02x:%02x:%lu", major(st.st_dev), minor(st.st_dev),
                static_cast<unsigned long>(st.st_ino));
  std::ifstream locks("/proc/locks");
  if (!locks) return false;  // who holds it cannot be known: leave the flag
  for (std::string line; std::getline(locks, line);) {
    std::istringstream fields(line);  // "1: FLOCK  ADVISORY  WRITE 1234 00:05:3 0 EOF"
    std::string number, type, mode, access, pid, where;
    if (fields >> number >> type >> mode >> access >> pid >> where && type == "FLOCK" &&
        where == file) {
      return false;  // a live client holds it
    }
  }
  return ::ioctl(slave_fd, TIOCNXCL) == 0;
}

void AbandonedExclusiveWatch::Poll(int slave_fd) {
  const auto now = std::chrono::steady_clock::now();
  if (now < next_) return;
  ReleaseAbandonedExclusive(slave_fd);  // a client killed while it held the pty
  next_ = now + std::chrono::milliseconds(250);
}

}  // namespace irdist::sim
