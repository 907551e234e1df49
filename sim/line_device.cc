#include "sim/line_device.h"

#include <fcntl.h>
#include <poll.h>
#include <pty.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <chrono>
#include <cstring>

#include "base/check.h"
#include "base/yaml_fields.h"

namespace irdist::sim {

// ----------------------------------------------------------------------------------------------
// The World's axes, shared by several emulators.

namespace {

struct WorldOwners {
  std::mutex mutex;
  std::map<const World*, std::map<const void*, bool>> moving;  // owner -> its axes move
};

WorldOwners& Owners() {
  static WorldOwners owners;
  return owners;
}

}  // namespace

bool IsRigAxis(const std::string& axis) {
  return axis == "slide" || axis == "pan" || axis == "tilt";
}

void WriteWorldAxes(World& world, const void* owner, const std::map<std::string, double>& axes,
                    bool moving) {
  WorldOwners& owners = Owners();
  std::lock_guard<std::mutex> lock(owners.mutex);
  auto& flags = owners.moving[&world];
  flags[owner] = moving;
  bool any_moving = false;
  for (const auto& [who, flag] : flags) any_moving = any_moving || flag;
  PoseState pose = world.Pose();
  for (const auto& [axis, value] : axes) {
    if (axis == "slide") pose.slide_mm = value;
    if (axis == "pan") pose.pan_deg = value;
    if (axis == "tilt") pose.tilt_deg = value;
  }
  world.SetPose(pose.slide_mm, pose.pan_deg, pose.tilt_deg, any_moving);
}

void ForgetWorldAxesOwner(World& world, const void* owner) {
  WorldOwners& owners = Owners();
  std::lock_guard<std::mutex> lock(owners.mutex);
  auto it = owners.moving.find(&world);
  if (it == owners.moving.end()) return;
  it->second.erase(owner);
  if (it->second.empty()) owners.moving.erase(it);
}

// ----------------------------------------------------------------------------------------------
// Motion in simulated time.

TrapezoidMove::TrapezoidMove(double from, double target, double start_s, double speed,
                             double accel)
    : from_(from), target_(target), start_s_(start_s), end_s_(start_s), accel_(accel) {
  const double distance = std::fabs(target - from);
  if (distance <= 0.0 || speed <= 0.0 || accel <= 0.0) return;
  if (distance >= speed * speed / accel) {
    peak_ = speed;
    ramp_s_ = speed / accel;
    end_s_ = start_s + 2.0 * ramp_s_ + (distance - speed * speed / accel) / speed;
  } else {
    ramp_s_ = std::sqrt(distance / accel);
    peak_ = accel * ramp_s_;
    end_s_ = start_s + 2.0 * ramp_s_;
  }
}

double TrapezoidMove::Position(double now_s) const {
  if (now_s >= end_s_) return target_;
  const double t = std::max(0.0, now_s - start_s_);
  const double total_s = end_s_ - start_s_;
  double covered = 0.0;
  if (t < ramp_s_) {
    covered = 0.5 * accel_ * t * t;
  } else if (t < total_s - ramp_s_) {
    covered = 0.5 * peak_ * ramp_s_ + peak_ * (t - ramp_s_);
  } else {
    const double left_s = total_s - t;
    covered = std::fabs(target_ - from_) - 0.5 * accel_ * left_s * left_s;
  }
  return from_ + (target_ >= from_ ? covered : -covered);
}

double TrapezoidMove::Velocity(double now_s) const {
  if (now_s >= end_s_ || now_s <= start_s_) return 0.0;
  const double t = now_s - start_s_;
  const double total_s = end_s_ - start_s_;
  const double speed = std::min({peak_, accel_ * t, accel_ * (total_s - t)});
  return target_ >= from_ ? speed : -speed;
}

// ----------------------------------------------------------------------------------------------
// LineDevice: pty, thread, reply faults.

LineDevice::LineDevice(World& world, std::string name, EmulatorFaults faults, std::uint64_t seed)
    : world_(world), name_(std::move(name)), faults_(std::move(faults)), rng_(seed) {
  std::string why;
  IRDIST_CHECK(faults_.IsValid(&why), name_ + ": " + why);
}

LineDevice::~LineDevice() {
  Stop();
  ForgetWorldAxesOwner(world_, this);
}

std::string LineDevice::Start() {
  IRDIST_CHECK(!running_, name_ + ": emulator already started");
  char path[256] = {};
  if (openpty(&master_fd_, &slave_fd_, path, nullptr, nullptr) != 0) {
    throw Error(name_ + " emulator: openpty failed: " + std::strerror(errno) +
                "; check that /dev/ptmx is available");
  }
  termios tio{};
  const bool raw = tcgetattr(slave_fd_, &tio) == 0 && (cfmakeraw(&tio), true) &&
                   tcsetattr(slave_fd_, TCSANOW, &tio) == 0;
  const int flags = fcntl(master_fd_, F_GETFL, 0);
  const bool nonblocking = flags >= 0 && fcntl(master_fd_, F_SETFL, flags | O_NONBLOCK) == 0;
  if (!raw || !nonblocking) {
    const std::string what = std::strerror(errno);
    CloseFds();
    throw Error(name_ + " emulator: cannot set the pty raw and non-blocking: " + what);
  }
  {
    std::lock_guard<std::mutex> lock(state_mutex_);
    stop_ = false;
    Advance(Now());
  }
  running_ = true;
  thread_ = std::thread([this] { Serve(); });
  return path;
}

void LineDevice::Stop() {
  if (!running_) return;
  {
    std::lock_guard<std::mutex> lock(state_mutex_);
    stop_ = true;
  }
  thread_.join();
  running_ = false;
  CloseFds();
}

void LineDevice::CloseFds() {
  if (master_fd_ >= 0) ::close(master_fd_);
  if (slave_fd_ >= 0) ::close(slave_fd_);
  master_fd_ = slave_fd_ = -1;
}

void LineDevice::PowerCycle() {
  std::lock_guard<std::mutex> lock(state_mutex_);
  ResetToPowerOn();
  pending_.clear();
  ++power_cycles_;
  StartBoot();
}

void LineDevice::StartBoot() {
  const double boot_s = BootSeconds();
  if (boot_s > 0.0) booting_until_s_ = Now() + boot_s;
}

bool LineDevice::Booting() const { return booting_until_s_ >= 0.0 && Now() < booting_until_s_; }

void LineDevice::MaybeEndBoot() {
  if (booting_until_s_ < 0.0 || Booting()) return;
  booting_until_s_ = -1.0;
  outbox_ += BootMessage();
}

void LineDevice::SetFaults(const EmulatorFaults& faults) {
  std::string why;
  IRDIST_CHECK(faults.IsValid(&why), name_ + ": " + why);
  std::lock_guard<std::mutex> lock(state_mutex_);
  std::lock_guard<std::mutex> faults_lock(faults_mutex_);
  faults_ = faults;
  power_cycle_done_ = false;  // a new power_cycle_after_s arms on the next move
  move_started_s_ = -1.0;
}

bool ReplyBitFlip::IsValid(std::string* why) const {
  std::string problem;
  if (bit < 0 || bit > 7) problem = "flip_bit must be 0-7";
  else if (count < 0) problem = "flip_count must be >= 0";
  if (why != nullptr) *why = problem;
  return problem.empty();
}

void LineDevice::SetReplyBitFlip(const ReplyBitFlip& flip) {
  std::string why;
  IRDIST_CHECK(flip.IsValid(&why), name_ + ": " + why);
  std::lock_guard<std::mutex> lock(faults_mutex_);
  flip_ = flip;
}

std::uint64_t LineDevice::RepliesFlipped() const {
  std::lock_guard<std::mutex> lock(faults_mutex_);
  return replies_flipped_;
}

// The chosen reply's bit, inverted (ReplyBitFlip), once per chosen message until `count` ran out.
void LineDevice::FlipChosenBit(const std::string& message, std::string* reply) {
  std::lock_guard<std::mutex> lock(faults_mutex_);
  if (flip_.command.empty() || flip_.count <= 0 || reply->empty() ||
      message.find(flip_.command) == std::string::npos) {
    return;
  }
  std::size_t text = reply->size();
  while (text > 0 && ((*reply)[text - 1] == '\r' || (*reply)[text - 1] == '\n')) --text;
  const long index = flip_.offset < 0 ? static_cast<long>(text) + flip_.offset : flip_.offset;
  if (index < 0 || index >= static_cast<long>(text)) return;
  (*reply)[static_cast<std::size_t>(index)] ^= static_cast<char>(1 << flip_.bit);
  --flip_.count;
  ++replies_flipped_;
}

EmulatorFaults LineDevice::Faults() const {
  std::lock_guard<std::mutex> lock(faults_mutex_);
  return faults_;
}

std::uint64_t LineDevice::PowerCycles() const {
  std::lock_guard<std::mutex> lock(state_mutex_);
  return power_cycles_;
}

std::uint64_t LineDevice::RepliesDropped() const {
  std::lock_guard<std::mutex> lock(state_mutex_);
  return replies_dropped_;
}

void LineDevice::NoteMoveStarted() {
  if (move_started_s_ < 0.0) move_started_s_ = Now();
}

void LineDevice::MaybePowerCycle() {
  const double after_s = Faults().power_cycle_after_s;
  if (after_s < 0.0 || power_cycle_done_ || move_started_s_ < 0.0) return;
  if (Now() - move_started_s_ < after_s) return;
  power_cycle_done_ = true;
  ResetToPowerOn();
  pending_.clear();
  ++power_cycles_;
  StartBoot();
}

void LineDevice::WaitInSimTime(std::unique_lock<std::mutex>& lock,
                               const std::function<bool()>& done) {
  while (!stop_) {
    Advance(Now());
    MaybePowerCycle();
    if (done()) return;
    lock.unlock();
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    lock.lock();
  }
}

void LineDevice::Serve() {
  char buffer[512];
  AbandonedExclusiveWatch exclusive;
  while (true) {
    exclusive.Poll(slave_fd_);
    std::string unsolicited;
    {
      std::unique_lock<std::mutex> lock(state_mutex_);
      if (stop_) return;
      current_lock_ = &lock;  // Advance may run a protocol's queued command that waits
      Advance(Now());
      MaybePowerCycle();
      MaybeEndBoot();
      current_lock_ = nullptr;
      unsolicited.swap(outbox_);
    }
    SendReply(unsolicited);
    pollfd ready{master_fd_, POLLIN, 0};
    const int polled = ::poll(&ready, 1, 2);
    if (polled < 0 && errno != EINTR) return;  // the pty is gone: nothing left to serve
    if (polled <= 0 || !(ready.revents & POLLIN)) continue;
    const ssize_t n = ::read(master_fd_, buffer, sizeof(buffer));
    if (n > 0) ServeBytes(buffer, static_cast<std::size_t>(n));
  }
}

void LineDevice::ServeBytes(const char* data, std::size_t size) {
  {
    std::lock_guard<std::mutex> lock(state_mutex_);
    if (Booting()) {  // a booting device's serial port is not listening yet
      pending_.clear();
      return;
    }
  }
  const std::string terminators = Terminators();
  for (std::size_t i = 0; i < size; ++i) {
    const char c = data[i];
    if (terminators.find(c) == std::string::npos) {
      if (pending_.size() < 4096) pending_ += c;
      continue;
    }
    if (pending_.empty()) continue;  // CR LF pairs, repeated delimiters
    std::string message;
    message.swap(pending_);
    std::string reply;
    {
      std::unique_lock<std::mutex> lock(state_mutex_);
      current_lock_ = &lock;
      reply = HandleMessage(message);
      current_lock_ = nullptr;
    }
    FlipChosenBit(message, &reply);
    SendReply(reply);
  }
}

void LineDevice::SendReply(const std::string& reply) {
  if (reply.empty()) return;
  const EmulatorFaults faults = Faults();
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  if (uniform(rng_) < faults.drop_rate) {
    std::lock_guard<std::mutex> lock(state_mutex_);
    ++replies_dropped_;
    return;
  }
  if (uniform(rng_) < faults.delay_rate) {
    std::unique_lock<std::mutex> lock(state_mutex_);
    const double until_s = Now() + faults.delay_s;
    current_lock_ = &lock;
    WaitInSimTime(lock, [this, until_s] { return Now() >= until_s; });
    current_lock_ = nullptr;
  }
  std::string bytes = reply;
  for (char& c : bytes) {
    if (c == '\r' || c == '\n' || uniform(rng_) >= faults.garble_rate) continue;
    const char garbled = static_cast<char>(c ^ (1 + static_cast<int>(uniform(rng_) * 126.0)));
    c = (garbled == '\r' || garbled == '\n') ? static_cast<char>(c ^ 0x20) : garbled;
  }
  std::size_t sent = 0;
  for (int attempts = 0; sent < bytes.size() && attempts < 1000; ++attempts) {
    const ssize_t n = ::write(master_fd_, bytes.data() + sent, bytes.size() - sent);
    if (n > 0) {
      sent += static_cast<std::size_t>(n);
    } else if (n < 0 && errno != EAGAIN && errno != EINTR) {
      return;  // the pty is gone
    } else {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  }
}

// ----------------------------------------------------------------------------------------------
// The rig file's entries of one device.

class DeviceSection {
 public:
  DeviceSection(YAML::Node node, std::string file, std::string context)
      : node_(std::move(node)), file_(std::move(file)), context_(std::move(context)) {}
  const YAML::Node& node() const { return node_; }
  const std::string& file() const { return file_; }
  const std::string& context() const { return context_; }

 private:
  YAML::Node node_;
  std::string file_;
  std::string context_;
};

namespace {

const std::vector<std::string> kFaultKeys = {
    "garble_rate", "drop_rate",  "delay_rate", "delay_s",   "power_cycle_after_s",
    "stuck_axis",  "flip_reply", "flip_byte",  "flip_bit",  "flip_count"};

YAML::Node Child(const YAML::Node& node, const std::string& key) {
  return node && node.IsMap() ? node[key] : YAML::Node();
}

// The numbers and the axes of station.devices.<name> (the station driver checks its own keys
// strictly; the emulator reads only what it needs).
void ReadStationEntry(const YAML::Node& entry, const EmulatorSpec& spec, DeviceKeys* keys) {
  if (!entry || !entry.IsMap()) return;
  const std::string where = "station.devices." + spec.name;
  for (const auto& item : entry) {
    if (!item.first.IsScalar()) {
      yaml_fields::Fail(spec.rig_path, item.first.Mark(), where + ": keys must be names");
    }
    const std::string key = item.first.Scalar();
    if (key == "axes") {
      if (!item.second.IsMap()) {
        yaml_fields::Fail(spec.rig_path, item.second.Mark(),
                          where + ".axes must be a map of rig axis to address");
      }
      for (const auto& axis : item.second) {
        keys->axes[yaml_fields::AsString(axis.first, spec.rig_path, where + ".axes keys")] =
            yaml_fields::AsString(axis.second, spec.rig_path, where + ".axes");
      }
    } else if (key == "origin_mm" || key == "origin_deg" || key == "direction") {
      keys->station_numbers[key] =
          yaml_fields::AsNumber(item.second, spec.rig_path, where + "." + key);
    }
  }
}

EmulatorFaults ReadFaults(const yaml_fields::MapReader& reader) {
  EmulatorFaults faults;
  faults.garble_rate = reader.Number("garble_rate", faults.garble_rate);
  faults.drop_rate = reader.Number("drop_rate", faults.drop_rate);
  faults.delay_rate = reader.Number("delay_rate", faults.delay_rate);
  faults.delay_s = reader.Number("delay_s", faults.delay_s);
  faults.power_cycle_after_s = reader.Number("power_cycle_after_s", faults.power_cycle_after_s);
  faults.stuck_axis = reader.String("stuck_axis", faults.stuck_axis);
  std::string why;
  if (!faults.IsValid(&why)) {
    yaml_fields::Fail(reader.File(), reader.Mark(),
                      "virtual.devices: " + why + " (docs/virtual-rig.md lists the fault keys)");
  }
  return faults;
}

ReplyBitFlip ReadFlip(const yaml_fields::MapReader& reader) {
  ReplyBitFlip flip;
  flip.command = reader.String("flip_reply", flip.command);
  flip.offset = static_cast<int>(reader.Number("flip_byte", flip.offset));
  flip.bit = static_cast<int>(reader.Number("flip_bit", flip.bit));
  flip.count = static_cast<int>(reader.Number("flip_count", flip.count));
  std::string why;
  if (!flip.IsValid(&why)) {
    yaml_fields::Fail(reader.File(), reader.Mark(),
                      "virtual.devices: " + why + " (docs/devices/README.md, fault keys)");
  }
  return flip;
}

}  // namespace

DeviceKeys ReadDeviceKeys(const EmulatorSpec& spec, const std::vector<std::string>& own_keys) {
  const YAML::Node root = yaml_fields::Parse(spec.rig_text, spec.rig_path);
  DeviceKeys keys;
  ReadStationEntry(Child(Child(Child(root, "station"), "devices"), spec.name), spec, &keys);
  // A device without a virtual.devices entry keeps every default. (Never assign to the missing
  // entry's node: yaml-cpp throws its own "invalid node", naming no file.)
  const YAML::Node found = Child(Child(Child(root, "virtual"), "devices"), spec.name);
  const YAML::Node entry =
      !found || found.IsNull() ? YAML::Node(YAML::NodeType::Map) : found;
  std::vector<std::string> allowed = own_keys;
  allowed.insert(allowed.end(), kFaultKeys.begin(), kFaultKeys.end());
  const std::string context = "virtual.devices." + spec.name;
  const yaml_fields::MapReader reader(entry, spec.rig_path, context, allowed);
  keys.faults = ReadFaults(reader);
  keys.flip = ReadFlip(reader);
  keys.section = std::make_shared<DeviceSection>(entry, spec.rig_path, context);
  return keys;
}

double DeviceKeys::Number(const std::string& key, double fallback) const {
  const YAML::Node value = section->node()[key];
  if (!value) return fallback;
  return yaml_fields::AsNumber(value, section->file(), section->context() + "." + key);
}

std::string DeviceKeys::Text(const std::string& key, const std::string& fallback) const {
  const YAML::Node value = section->node()[key];
  if (!value) return fallback;
  return yaml_fields::AsString(value, section->file(), section->context() + "." + key);
}

bool DeviceKeys::Boolean(const std::string& key, bool fallback) const {
  const YAML::Node value = section->node()[key];
  if (!value) return fallback;
  return yaml_fields::AsBoolean(value, section->file(), section->context() + "." + key);
}

void DeviceKeys::Fail(const std::string& key, const std::string& message) const {
  const YAML::Node value = section->node()[key];
  const YAML::Mark mark = value ? value.Mark() : section->node().Mark();
  yaml_fields::Fail(section->file(), mark, section->context() + "." + key + ": " + message);
}

}  // namespace irdist::sim
