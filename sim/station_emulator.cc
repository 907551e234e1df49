#include "sim/station_emulator.h"

#include <fcntl.h>
#include <poll.h>
#include <pty.h>
#include <termios.h>
#include <unistd.h>

#include <yaml-cpp/yaml.h>

#include <boost/crc.hpp>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <map>
#include <mutex>
#include <random>
#include <sstream>
#include <thread>
#include <vector>

#include "base/check.h"
#include "base/yaml_fields.h"
#include "sim/device_emulator.h"

namespace irdist::sim {

namespace {

constexpr std::size_t kMaxLineBytes = 128;

// CRC-8, polynomial x^8 + x^2 + x + 1 (0x07), initial value 0, no reflection: the protocol's
// per-line checksum (docs/station-protocol.md). CRC-8("123456789") = 0xF4.
std::uint8_t Crc8(const std::string& text) {
  boost::crc_optimal<8, 0x07, 0x00, 0x00, false, false> crc;
  crc.process_bytes(text.data(), text.size());
  return static_cast<std::uint8_t>(crc.checksum());
}

template <typename T>
void ReadKey(const YAML::Node& node, const char* key, T* value, const std::string& where) {
  const YAML::Node child = node[key];
  if (!child) return;
  try {
    *value = child.as<T>();
  } catch (const YAML::Exception& e) {
    throw Error(where + ":" + std::to_string(child.Mark().line + 1) + ":" +
                std::to_string(child.Mark().column + 1) + ": " + key + ": " + e.what() +
                "; fix the value's type (see docs/station-protocol.md, emulator options)");
  }
}

void ReadAxis(const YAML::Node& node, AxisOptions* axis, const std::string& where) {
  if (!node) return;
  // Strict: a misspelt key is an InputError with file:line, never silently ignored.
  const yaml_fields::MapReader keys(node, where, "virtual.station axis",
                                    {"min", "max", "home", "speed", "accel", "settle_s",
                                     "power_on", "max_speed"});
  ReadKey(node, "min", &axis->min, where);
  ReadKey(node, "max", &axis->max, where);
  ReadKey(node, "home", &axis->home, where);
  ReadKey(node, "speed", &axis->speed, where);
  ReadKey(node, "accel", &axis->accel, where);
  ReadKey(node, "settle_s", &axis->settle_s, where);
  ReadKey(node, "power_on", &axis->power_on, where);
  ReadKey(node, "max_speed", &axis->max_speed, where);
}

}  // namespace

namespace {

// The rig's station.limits become the emulator's soft limits (and current range).
void ApplyStationLimits(const YAML::Node& root, const std::string& rig_path,
                        EmulatorOptions* options) {
  auto limit = [&](const YAML::Node& limits, const char* key, AxisOptions* axis) {
    const YAML::Node pair = limits[key];
    if (!pair) return;
    if (!pair.IsSequence() || pair.size() != 2) {
      throw Error(rig_path + ":" + std::to_string(pair.Mark().line + 1) + ": station.limits." +
                  key + " must be a list [min, max]; fix the rig file");
    }
    try {
      axis->min = pair[0].as<double>();
      axis->max = pair[1].as<double>();
    } catch (const YAML::Exception& e) {
      throw Error(rig_path + ":" + std::to_string(pair.Mark().line + 1) + ": station.limits." +
                  key + ": " + e.what() + "; fix the rig file");
    }
  };
  const YAML::Node station = root["station"];
  if (!station || !station["limits"]) return;
  const YAML::Node limits = station["limits"];
  limit(limits, "slide_mm", &options->slide);
  limit(limits, "pan_deg", &options->pan);
  limit(limits, "tilt_deg", &options->tilt);
  AxisOptions bias;
  limit(limits, "bias_ma", &bias);
  if (limits["bias_ma"]) options->max_current_ma = bias.max;
  for (AxisOptions* a : {&options->slide, &options->pan, &options->tilt}) {
    a->home = std::clamp(a->home, a->min, a->max);
    a->power_on = std::clamp(a->power_on, a->min, a->max);
  }
}

// `virtual.station:`, strictly: an unknown key is an InputError with file:line.
void ReadVirtualStation(const YAML::Node& node, const std::string& rig_path,
                        EmulatorOptions* o) {
  const yaml_fields::MapReader keys(
      node, rig_path, "virtual.station",
      {"slide", "pan", "tilt", "homing_speed_factor", "max_current_ma", "current_noise_ma",
       "min_trigger_width_us", "min_trigger_period_us", "max_trigger_count", "reply_latency_s",
       "seed", "garble_rate", "drop_rate", "delay_rate", "delay_s", "reboot_after_s",
       "stuck_axis", "missed_pulse_rate", "open_circuit", "refuse_current_off_in_estop",
       "fault_at_move", "fault"});
  ReadAxis(node["slide"], &o->slide, rig_path);
  ReadAxis(node["pan"], &o->pan, rig_path);
  ReadAxis(node["tilt"], &o->tilt, rig_path);
  ReadKey(node, "homing_speed_factor", &o->homing_speed_factor, rig_path);
  ReadKey(node, "max_current_ma", &o->max_current_ma, rig_path);
  ReadKey(node, "current_noise_ma", &o->current_noise_ma, rig_path);
  ReadKey(node, "min_trigger_width_us", &o->min_trigger_width_us, rig_path);
  ReadKey(node, "min_trigger_period_us", &o->min_trigger_period_us, rig_path);
  ReadKey(node, "max_trigger_count", &o->max_trigger_count, rig_path);
  ReadKey(node, "reply_latency_s", &o->reply_latency_s, rig_path);
  ReadKey(node, "seed", &o->seed, rig_path);
  ReadKey(node, "garble_rate", &o->garble_rate, rig_path);
  ReadKey(node, "drop_rate", &o->drop_rate, rig_path);
  ReadKey(node, "delay_rate", &o->delay_rate, rig_path);
  ReadKey(node, "delay_s", &o->delay_s, rig_path);
  ReadKey(node, "reboot_after_s", &o->reboot_after_s, rig_path);
  ReadKey(node, "stuck_axis", &o->stuck_axis, rig_path);
  ReadKey(node, "missed_pulse_rate", &o->missed_pulse_rate, rig_path);
  ReadKey(node, "open_circuit", &o->open_circuit, rig_path);
  ReadKey(node, "refuse_current_off_in_estop", &o->refuse_current_off_in_estop, rig_path);
  ReadKey(node, "fault_at_move", &o->fault_at_move, rig_path);
  ReadKey(node, "fault", &o->fault, rig_path);
}

}  // namespace

EmulatorOptions LoadEmulatorOptions(const std::string& rig_path) {
  EmulatorOptions options;
  YAML::Node root;
  try {
    root = yaml_fields::Parse(yaml_fields::ReadFile(rig_path), rig_path);
  } catch (const YAML::Exception& e) {
    throw Error("cannot read rig file " + rig_path + ": " + e.what() +
                "; fix the path or the YAML syntax");
  }
  ApplyStationLimits(root, rig_path, &options);
  const YAML::Node virt = root["virtual"];
  const YAML::Node node = virt ? virt["station"] : YAML::Node();
  if (node) ReadVirtualStation(node, rig_path, &options);
  std::string why;
  if (!options.IsValid(&why)) {
    throw Error(rig_path + ": " + why + "; fix the rig file");
  }
  return options;
}
// ------------------------------------------------------------------------------------------------
// The pty layer. One thread owns the pty master; it reads framed lines and hands their commands to
// the station model. Every model call is made under `mutex` so that the control setters may be
// called from any thread.

struct StationEmulator::Impl : StationEffects {
  struct PendingReply {
    double send_at_s;
    std::string bytes;
  };

  World& world;
  mutable std::mutex mutex;
  StationModel model;

  int master_fd = -1;
  int slave_fd = -1;
  std::string slave_path;
  std::atomic<bool> stop{false};
  std::thread thread;

  // Framing and link state.
  std::string rx;
  bool rx_overflow = false;
  std::string last_request;  // "#seq command" of the last executed request
  std::string last_reply;    // its framed reply, re-sent on a retransmission
  std::vector<PendingReply> pending;
  std::uint64_t lines = 0, dropped = 0;

  Impl(World& w, EmulatorOptions o) : world(w), model(*this, std::move(o)) {}

  double Now() const { return world.clock().Now(); }
  const EmulatorOptions& options() { return model.options(); }

  // --- StationEffects: the model's outputs go to the shared World ---
  void SetPose(double slide_mm, double pan_deg, double tilt_deg, bool moving) override {
    world.SetPose(slide_mm, pan_deg, tilt_deg, moving);
  }
  void SetAxisMotion(RigAxis axis, const MotionProfile& profile) override {
    world.SetAxisMotion(axis, profile);
  }
  void SetCurrent(double bias_ma) override { world.SetCurrent(bias_ma); }
  void FireTrigger() override {
    mutex.unlock();  // the sink may render a frame; never hold our lock across it
    world.FireTrigger();
    mutex.lock();
  }
  void PoweredUp() override {
    rx.clear();
    last_request.clear();
    last_reply.clear();
    pending.clear();
  }

  std::string Frame(const std::string& seq, const std::string& body) const {
    const std::string text = "#" + seq + " " + body;
    char cs[4];
    std::snprintf(cs, sizeof(cs), "%02X", Crc8(text));
    return text + "*" + cs + "\r\n";
  }

  // Handles one received line (without its line end).
  void OnLine(const std::string& line, double now) {
    ++lines;
    // Frame: "#<seq> <command>*<hh>".
    const std::size_t star = line.rfind('*');
    const std::size_t space = line.find(' ');
    if (line.size() < 2 || line[0] != '#' || star == std::string::npos ||
        star + 3 != line.size() || space == std::string::npos || space > star) {
      model.PushError(-102);
      return;  // unframed: no seq to answer to
    }
    const std::string text = line.substr(0, star);
    unsigned int cs = 0;
    if (std::sscanf(line.c_str() + star + 1, "%2x", &cs) != 1 ||
        static_cast<std::uint8_t>(cs) != Crc8(text)) {
      model.PushError(203);
      return;  // the seq may be damaged too: stay silent, the host retransmits
    }
    const std::string seq = line.substr(1, space - 1);
    long long seq_value = 0;
    if (!ParseProtocolInt(seq, &seq_value) || seq_value < 0 || seq_value > 9999 || seq[0] == '-' ||
        seq[0] == '+') {
      model.PushError(-102);
      return;
    }
    std::string reply;
    model.NoteValidRequest(now);  // the link is alive (docs/station-protocol.md, link loss)
    if (text == last_request && !last_reply.empty()) {
      reply = last_reply;  // retransmission: answer again, do not execute again
    } else {
      reply = Frame(seq, model.Execute(line.substr(space + 1, star - space - 1), now));
      last_request = text;
      last_reply = reply;
    }
    Send(reply, now);
  }

  void Send(std::string bytes, double now) {
    if (model.Silent() || model.Chance(options().drop_rate)) {
      ++dropped;
      return;
    }
    for (char& c : bytes) {
      if (model.Chance(options().garble_rate)) {
        char g;
        do {
          g = static_cast<char>(std::uniform_int_distribution<int>(1, 126)(model.Random()));
        } while (g == c);
        c = g;
      }
    }
    double at = now + options().reply_latency_s;
    if (model.Chance(options().delay_rate)) at += options().delay_s;
    pending.push_back({at, std::move(bytes)});
  }

  void WriteAll(const std::string& bytes) {
    std::size_t done = 0;
    while (done < bytes.size() && !stop) {
      const ssize_t n = write(master_fd, bytes.data() + done, bytes.size() - done);
      if (n > 0) {
        done += static_cast<std::size_t>(n);
      } else if (n < 0 && (errno == EAGAIN || errno == EINTR)) {
        std::this_thread::sleep_for(std::chrono::microseconds(200));
      } else {
        return;  // the pty is gone; Stop() will follow
      }
    }
  }

  void Loop() {
    char buf[512];
    AbandonedExclusiveWatch exclusive;
    while (!stop) {
      exclusive.Poll(slave_fd);
      // Wait for input, at most until the next scheduled event (in host time).
      double wait_host_s = 0.002;
      {
        std::lock_guard<std::mutex> lock(mutex);
        const double now = Now();
        auto until = [&](double t) {
          wait_host_s = std::min(wait_host_s, std::max(0.0, (t - now)) / world.clock().time_scale());
        };
        if (const auto pulse_s = model.NextPulseS()) until(*pulse_s);
        for (const PendingReply& p : pending) until(p.send_at_s);
      }
      pollfd pfd{master_fd, POLLIN, 0};
      const timespec ts{0, static_cast<long>(wait_host_s * 1e9)};
      const int ready = ppoll(&pfd, 1, &ts, nullptr);
      std::string out;
      {
        std::lock_guard<std::mutex> lock(mutex);
        double now = Now();
        model.Advance(now);
        if (ready > 0 && (pfd.revents & POLLIN)) {
          const ssize_t n = read(master_fd, buf, sizeof(buf));
          if (n > 0 && !model.Booting()) {
            for (ssize_t i = 0; i < n; ++i) {
              const char c = buf[i];
              if (c == '\n') {
                if (!rx_overflow) OnLine(rx, now);
                rx.clear();
                rx_overflow = false;
              } else if (c != '\r') {
                if (rx.size() >= kMaxLineBytes) {
                  if (!rx_overflow) model.PushError(205);
                  rx_overflow = true;
                } else {
                  rx.push_back(c);
                }
              }
            }
          }
          now = Now();
          model.Advance(now);
        }
        // Replies that are due, in order of their due time.
        std::stable_sort(pending.begin(), pending.end(),
                         [](const PendingReply& a, const PendingReply& b) {
                           return a.send_at_s < b.send_at_s;
                         });
        std::size_t k = 0;
        while (k < pending.size() && pending[k].send_at_s <= now) out += pending[k++].bytes;
        pending.erase(pending.begin(), pending.begin() + static_cast<long>(k));
      }
      if (!out.empty()) WriteAll(out);
    }
  }
};

StationEmulator::StationEmulator(World& world, EmulatorOptions options)
    : impl_(std::make_unique<Impl>(world, std::move(options))) {}

StationEmulator::~StationEmulator() { Stop(); }

std::string StationEmulator::Start() {
  IRDIST_CHECK(!impl_->thread.joinable(), "StationEmulator::Start called twice");
  char name[256] = {0};
  if (openpty(&impl_->master_fd, &impl_->slave_fd, name, nullptr, nullptr) != 0) {
    throw Error(std::string("station emulator: openpty failed: ") + std::strerror(errno) +
                "; check that /dev/ptmx is available (devpts mounted)");
  }
  termios tio{};
  if (tcgetattr(impl_->slave_fd, &tio) == 0) {
    cfmakeraw(&tio);
    tcsetattr(impl_->slave_fd, TCSANOW, &tio);
  }
  const int flags = fcntl(impl_->master_fd, F_GETFL);
  fcntl(impl_->master_fd, F_SETFL, flags | O_NONBLOCK);
  impl_->slave_path = name;
  {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    impl_->model.PowerOn(impl_->Now());
  }
  impl_->stop = false;
  impl_->thread = std::thread([this] { impl_->Loop(); });
  return impl_->slave_path;
}

void StationEmulator::Stop() {
  impl_->stop = true;
  if (impl_->thread.joinable()) impl_->thread.join();
  if (impl_->master_fd >= 0) close(impl_->master_fd);
  if (impl_->slave_fd >= 0) close(impl_->slave_fd);
  impl_->master_fd = impl_->slave_fd = -1;
}

void StationEmulator::SetGarbleRate(double rate) {
  IRDIST_CHECK(rate >= 0.0 && rate <= 1.0, "rate ", rate);
  std::lock_guard<std::mutex> lock(impl_->mutex);
  impl_->model.options().garble_rate = rate;
}
void StationEmulator::SetDropRate(double rate) {
  IRDIST_CHECK(rate >= 0.0 && rate <= 1.0, "rate ", rate);
  std::lock_guard<std::mutex> lock(impl_->mutex);
  impl_->model.options().drop_rate = rate;
}
void StationEmulator::SetDelay(double rate, double delay_s) {
  IRDIST_CHECK(rate >= 0.0 && rate <= 1.0 && delay_s >= 0.0, "rate ", rate, " delay ", delay_s);
  std::lock_guard<std::mutex> lock(impl_->mutex);
  impl_->model.options().delay_rate = rate;
  impl_->model.options().delay_s = delay_s;
}
void StationEmulator::SetStuckAxis(const std::string& axis) {
  IRDIST_CHECK(axis.empty() || axis == "slide" || axis == "pan" || axis == "tilt", axis);
  std::lock_guard<std::mutex> lock(impl_->mutex);
  impl_->model.options().stuck_axis = axis;
}
void StationEmulator::SetMissedPulseRate(double rate) {
  IRDIST_CHECK(rate >= 0.0 && rate <= 1.0, "rate ", rate);
  std::lock_guard<std::mutex> lock(impl_->mutex);
  impl_->model.options().missed_pulse_rate = rate;
}
void StationEmulator::RebootDuringNextMove(double after_s) {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  impl_->model.RebootDuringNextMove(after_s);
}
void StationEmulator::PressEmergencyStop() {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  impl_->model.PressEmergencyStop(impl_->Now());
}
void StationEmulator::Reboot() {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  impl_->model.Reboot(impl_->Now());
}
std::string StationEmulator::BootId() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->model.BootId();
}
std::uint64_t StationEmulator::Reboots() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->model.Reboots();
}
std::uint64_t StationEmulator::LinesReceived() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->lines;
}
std::uint64_t StationEmulator::RepliesDropped() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->dropped;
}

}  // namespace irdist::sim
