#include "sim/station_emulator.h"

#include <fcntl.h>
#include <poll.h>
#include <pty.h>
#include <termios.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <mutex>
#include <thread>

#include "base/check.h"

namespace irdist::sim {

namespace {
bool AxisValid(const AxisOptions& a, const char* name, std::string* why) {
  auto fail = [&](const std::string& m) {
    if (why) *why = std::string(name) + ": " + m;
    return false;
  };
  if (!(a.min < a.max)) return fail("min must be < max");
  if (a.home < a.min || a.home > a.max) return fail("home must lie within [min, max]");
  if (!(a.speed > 0)) return fail("speed must be > 0");
  if (!(a.accel > 0)) return fail("accel must be > 0");
  if (a.settle_s < 0) return fail("settle_s must be >= 0");
  return true;
}
}  // namespace

bool EmulatorOptions::IsValid(std::string* why) const {
  if (!AxisValid(slide, "slide", why) || !AxisValid(pan, "pan", why) ||
      !AxisValid(tilt, "tilt", why)) {
    return false;
  }
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  auto rate_ok = [](double r) { return r >= 0.0 && r <= 1.0; };
  if (!(homing_speed_factor > 0 && homing_speed_factor <= 1)) {
    return fail("homing_speed_factor must be in (0, 1]");
  }
  if (!(max_current_ma > 0)) return fail("max_current_ma must be > 0");
  if (current_noise_ma < 0) return fail("current_noise_ma must be >= 0");
  if (!rate_ok(garble_rate) || !rate_ok(drop_rate) || !rate_ok(delay_rate) ||
      !rate_ok(missed_pulse_rate)) {
    return fail("fault rates must be in [0, 1]");
  }
  if (!stuck_axis.empty() && stuck_axis != "slide" && stuck_axis != "pan" &&
      stuck_axis != "tilt") {
    return fail("stuck_axis must be empty, slide, pan or tilt");
  }
  return true;
}

EmulatorOptions LoadEmulatorOptions(const std::string& rig_path) { return EmulatorOptions{}; }

struct StationEmulator::Impl {
  World& world;
  EmulatorOptions options;
  int master_fd = -1;
  int slave_fd = -1;
  std::atomic<bool> stop{false};
  std::thread thread;
  Impl(World& w, EmulatorOptions o) : world(w), options(std::move(o)) {}
};

StationEmulator::StationEmulator(World& world, EmulatorOptions options)
    : impl_(std::make_unique<Impl>(world, std::move(options))) {}
StationEmulator::~StationEmulator() { Stop(); }

std::string StationEmulator::Start() {
  char name[256] = {0};
  if (openpty(&impl_->master_fd, &impl_->slave_fd, name, nullptr, nullptr) != 0) {
    throw Error(std::string("station emulator: openpty failed: ") + std::strerror(errno));
  }
  return name;
}

void StationEmulator::Stop() {
  impl_->stop = true;
  if (impl_->thread.joinable()) impl_->thread.join();
  if (impl_->master_fd >= 0) close(impl_->master_fd);
  if (impl_->slave_fd >= 0) close(impl_->slave_fd);
  impl_->master_fd = impl_->slave_fd = -1;
}

void StationEmulator::SetGarbleRate(double rate) { impl_->options.garble_rate = rate; }
void StationEmulator::SetDropRate(double rate) { impl_->options.drop_rate = rate; }
void StationEmulator::SetDelay(double rate, double delay_s) {
  impl_->options.delay_rate = rate;
  impl_->options.delay_s = delay_s;
}
void StationEmulator::SetStuckAxis(const std::string& axis) { impl_->options.stuck_axis = axis; }
void StationEmulator::SetMissedPulseRate(double rate) { impl_->options.missed_pulse_rate = rate; }
void StationEmulator::RebootDuringNextMove(double after_s) { impl_->options.reboot_after_s = after_s; }
void StationEmulator::Reboot() {}
std::string StationEmulator::BootId() const { return ""; }
std::uint64_t StationEmulator::Reboots() const { return 0; }
std::uint64_t StationEmulator::LinesReceived() const { return 0; }
std::uint64_t StationEmulator::RepliesDropped() const { return 0; }

}  // namespace irdist::sim
