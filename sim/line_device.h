#pragma once
// sim-internal: what the line-oriented device emulators (zaber_ascii, flir_ptu, scpi_source) share
// and what is not their devices' protocol: the pseudo-terminal (openpty, raw mode), the serving
// thread, the reply faults of EmulatorFaults (garbled, dropped, delayed replies; the power cycle
// armed by the first move), the World's axes written by several emulators at once, and the
// strict reading of the rig file's `station.devices.<name>` and `virtual.devices.<name>` entries.
// Each protocol lives in its own file and implements the three hooks of LineDevice.

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "sim/device_emulator.h"
#include "sim/world.h"

namespace irdist::sim {

// The rig axes of the World: "slide" (mm), "pan" and "tilt" (deg).
bool IsRigAxis(const std::string& axis);

// Writes some axes of the World's pose and leaves the others as they are. `owner` (one per
// emulator) has its own moving flag: the World is moving while any owner's axes move.
void WriteWorldAxes(World& world, const void* owner, const std::map<std::string, double>& axes,
                    bool moving);
void ForgetWorldAxesOwner(World& world, const void* owner);

// A trapezoidal move from rest to rest in simulated time (unit of the axis: microsteps,
// positions...): accelerates at `accel`, cruises at `speed`, decelerates to `target`.
class TrapezoidMove {
 public:
  TrapezoidMove() = default;
  TrapezoidMove(double from, double target, double start_s, double speed, double accel);
  double Position(double now_s) const;
  double Velocity(double now_s) const;  // signed
  bool Done(double now_s) const { return now_s >= end_s_; }
  double Target() const { return target_; }
  double DurationS() const { return end_s_ - start_s_; }

 private:
  double from_ = 0.0, target_ = 0.0, start_s_ = 0.0, end_s_ = 0.0;
  double accel_ = 1.0, peak_ = 0.0, ramp_s_ = 0.0;  // peak speed and ramp duration
};

// One flipped bit in chosen replies (`virtual.devices.<name>.flip_reply` and its keys; also a
// test hook): the reply to each of the first `count` messages containing `command` leaves with
// bit `bit` of its byte `offset` inverted (offset < 0 counts from the end of the reply's text,
// its line end excluded: -1 is its last character). "1" -> "0" is bit 0 of the last byte;
// "1651" -> "16=1" is bit 3 of the byte before last.
struct ReplyBitFlip {
  std::string command;  // empty: off
  int offset = -1;
  int bit = 0;          // 0-7
  int count = 1;        // replies to damage
  bool IsValid(std::string* why) const;
};

// A line-protocol device on its own pty, served by its own thread. The thread reads bytes,
// splits them into messages at the device's terminators, hands each to HandleMessage (under the
// state lock) and sends what it returns through the reply faults. Between messages it calls
// Advance (under the lock) to move the device's axes in simulated time.
class LineDevice : public DeviceEmulator {
 public:
  LineDevice(World& world, std::string name, EmulatorFaults faults, std::uint64_t seed);
  ~LineDevice() override;

  std::string Start() override;
  void Stop() override;
  void PowerCycle() override;
  void SetFaults(const EmulatorFaults& faults) override;
  void SetReplyBitFlip(const ReplyBitFlip& flip);

  // --- observation, for tests ---
  std::uint64_t RepliesFlipped() const;
  std::uint64_t PowerCycles() const;
  std::uint64_t RepliesDropped() const;

 protected:
  // Bytes that end a message (e.g. "\n" or "\r\n" for Zaber and SCPI, "\r\n " for the PTU).
  virtual std::string Terminators() const = 0;
  // One message (without its terminator); returns the reply bytes, terminators included ("" =
  // no reply). Called with the state lock held.
  virtual std::string HandleMessage(const std::string& message) = 0;
  // Moves the axes to simulated time `now_s` and writes them into the World (lock held).
  virtual void Advance(double now_s) = 0;
  // Returns the device to its power-on state (lock held).
  virtual void ResetToPowerOn() = 0;
  // How long the device boots after a power cycle (simulated seconds): it hears and answers
  // nothing meanwhile (bytes sent to it are lost). 0: at once (lock held).
  virtual double BootSeconds() const { return 0.0; }
  // What the device prints on its own when its boot ends (an alert), terminators included
  // ("" = nothing; lock held).
  virtual std::string BootMessage() { return ""; }

  // Called by the protocol when a move starts: arms the power cycle of the faults.
  void NoteMoveStarted();
  // Queues a message the device sends on its own (an alert, the PTU's limit-hit report), sent
  // by the serving thread after the current Advance (lock held).
  void SendUnsolicited(const std::string& bytes) { outbox_ += bytes; }
  // Runs Advance until `done` holds or the emulator stops (used by commands that, on the real
  // device, answer only when motion ends, e.g. the PTU's await). Lock held on entry and exit.
  void WaitInSimTime(std::unique_lock<std::mutex>& lock, const std::function<bool()>& done);
  EmulatorFaults Faults() const;  // a copy (lock held or not)
  double Now() const { return world_.clock().Now(); }
  World& world() { return world_; }
  std::unique_lock<std::mutex>& CurrentLock() { return *current_lock_; }
  // Whether the serving thread holds the state lock through a unique_lock CurrentLock() gives
  // (in HandleMessage, and in Advance when the serving thread calls it): only then may a
  // protocol run a command that waits in simulated time.
  bool HasCurrentLock() const { return current_lock_ != nullptr; }

  mutable std::mutex state_mutex_;

 private:
  void Serve();
  void ServeBytes(const char* data, std::size_t size);
  void SendReply(const std::string& reply);
  void FlipChosenBit(const std::string& message, std::string* reply);
  void MaybePowerCycle();
  void StartBoot();
  bool Booting() const;  // lock held
  void MaybeEndBoot();   // lock held
  void CloseFds();

  World& world_;
  std::string name_;
  mutable std::mutex faults_mutex_;
  EmulatorFaults faults_;
  ReplyBitFlip flip_;
  std::uint64_t replies_flipped_ = 0;
  std::mt19937_64 rng_;
  int master_fd_ = -1;
  int slave_fd_ = -1;
  std::thread thread_;
  bool running_ = false;
  bool stop_ = false;
  std::string pending_;
  std::string outbox_;  // unsolicited messages to send (SendUnsolicited)
  double move_started_s_ = -1.0;
  bool power_cycle_done_ = false;
  std::uint64_t power_cycles_ = 0;
  double booting_until_s_ = -1.0;  // < 0: not booting
  std::uint64_t replies_dropped_ = 0;
  std::unique_lock<std::mutex>* current_lock_ = nullptr;
};

// The two rig-file entries of one device, read with base/yaml_fields.h. The YAML nodes stay in
// the .cc; protocols read their keys through these helpers.
class DeviceSection;
struct DeviceKeys {
  // station.devices.<name>: its `axes:` map (rig axis -> device-specific address text) and the
  // numbers it may carry (origin_mm, origin_deg, direction...), read by key when present.
  std::map<std::string, std::string> axes;
  std::map<std::string, double> station_numbers;
  // virtual.devices.<name>: every key (faults included) as text, checked against the protocol's
  // list; numbers are read with Number() below so errors carry file:line.
  std::shared_ptr<const DeviceSection> section;
  EmulatorFaults faults;
  ReplyBitFlip flip;  // flip_reply, flip_byte, flip_bit, flip_count

  double Number(const std::string& key, double fallback) const;
  std::string Text(const std::string& key, const std::string& fallback) const;
  bool Boolean(const std::string& key, bool fallback) const;
  // Throws InputError at the entry's position (file:line) with `message`.
  [[noreturn]] void Fail(const std::string& key, const std::string& message) const;
};

// Reads both entries of `spec.name`; `own_keys` are the protocol's virtual.devices keys (the
// fault keys are added). Unknown keys in virtual.devices.<name> are InputErrors with file:line.
DeviceKeys ReadDeviceKeys(const EmulatorSpec& spec, const std::vector<std::string>& own_keys);

}  // namespace irdist::sim
