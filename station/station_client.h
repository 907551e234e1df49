#pragma once
// The station client: the operations of docs/station-protocol.md over a Transport, with request
// framing, sequence matching, retries of lost or damaged replies, move completion by polling, and
// recovery from a station reboot (detected from the boot id).

#include <chrono>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "station/device.h"
#include "station/frame.h"
#include "station/motion.h"
#include "station/transport.h"

namespace irdist {

struct ClientOptions {
  std::chrono::milliseconds reply_timeout{500};  // per attempt, host time
  int max_retries = 8;                   // resends of one request after a lost or damaged reply
  std::chrono::milliseconds poll_period{10};     // between position/state polls while waiting
  std::chrono::milliseconds move_timeout{300000};  // a move or homing not settled by then fails
  double slide_tolerance_mm = 0.01;      // |position - target| accepted as arrived
  double angle_tolerance_deg = 0.01;
  // Consecutive IDLE + in-tolerance polls that end a move: IDLE means settled (the protocol's
  // section 4), so one is enough; an IDLE off the target fails the move on its second poll.
  int settled_polls = 1;
  int max_move_attempts = 2;             // a move that ends out of tolerance is reissued this often
  bool recover_on_reboot = true;         // after a reboot: re-home and restore the IRED current
  bool IsValid(std::string* why) const;
};

// The station refused a command (an ERR reply) or a move/homing failed. what() names the command,
// the station's error code and message, and what to do.
class StationError : public Error {
 public:
  StationError(int code, const std::string& message) : Error(message), code_(code) {}
  int code() const { return code_; }  // the protocol's error code (0 when not from a reply)

 private:
  int code_;
};

// The station power-cycled (its boot id changed). When ClientOptions::recover_on_reboot is set the
// client has already re-homed and restored the IRED current; the caller must retake the point
// (whatever was captured since the last settled pose is not trustworthy).
class StationRebooted : public DeviceRestarted {
 public:
  StationRebooted(std::string old_boot_id, std::string new_boot_id, bool recovered)
      : DeviceRestarted("station rebooted (boot id " + old_boot_id + " -> " + new_boot_id + ")" +
              (recovered ? "; re-homed and IRED current restored: retake the point"
                         : "; home it and restore the current before continuing"),
                        recovered),
        old_boot_id_(std::move(old_boot_id)),
        new_boot_id_(std::move(new_boot_id)) {}
  const std::string& old_boot_id() const { return old_boot_id_; }
  const std::string& new_boot_id() const { return new_boot_id_; }

 private:
  std::string old_boot_id_, new_boot_id_;
};

enum class StationState { kUnhomed, kHoming, kIdle, kMoving, kSettling, kEStop, kUnknown };
std::string StationStateName(StationState state);

struct StationStatus {
  StationState state = StationState::kUnknown;
  std::string boot_id;
};

struct StationIdentity {
  std::string vendor, model, serial, firmware, boot_id;
};

struct StationErrorEntry {
  int code = 0;
  std::string message;
};

struct PulseCounter {
  std::uint64_t total = 0;      // pulses emitted since power-up
  std::uint64_t remaining = 0;  // pulses still to come in the running train
};

struct SoftLimits {
  double slide_min_mm = 0, slide_max_mm = 0;
  double pan_min_deg = 0, pan_max_deg = 0;
  double tilt_min_deg = 0, tilt_max_deg = 0;
};

// Link statistics, for the run's report.
struct ClientStats {
  std::uint64_t requests = 0;   // distinct requests
  std::uint64_t resends = 0;    // retransmissions
  std::uint64_t timeouts = 0;   // attempts without a reply in time
  std::uint64_t damaged = 0;    // reply lines rejected (framing, checksum)
  std::uint64_t stale = 0;      // valid replies to an earlier request, skipped
  std::uint64_t reboots = 0;    // station reboots detected
  std::string BriefReport() const;
};

class StationClient {
 public:
  // `transport` must outlive the client.
  explicit StationClient(Transport& transport, ClientOptions options = {});

  // *IDN?; remembers the boot id against which reboots are detected.
  StationIdentity Identify();
  // Homes all axes and waits until settled. Throws StationError if homing fails.
  void Home();
  // Absolute move (rounded to 0.01 mm / 0.01 deg); returns once every axis is within tolerance
  // and the station reports IDLE on settled_polls consecutive polls. Throws StationError (limits,
  // not homed, e-stop, an axis that does not arrive), StationRebooted, LinkError.
  void MoveTo(const StationPosition& target);
  // MoveTo in two halves, so that other devices' moves overlap: StartMove sends MOVE (throws
  // StationError on a refusal such as -222), WaitMoveSettled polls until settled at that target
  // (reissuing it when it ended off target, as MoveTo).
  void StartMove(const StationPosition& target);
  void WaitMoveSettled();
  StationPosition Position();
  // STAT?; throws StationRebooted when the boot id changed (after recovery, see options).
  StationStatus Status();
  SoftLimits GetSoftLimits();
  // axis: "SLIDE", "PAN" or "TILT"; limits in mm or deg.
  void SetSoftLimit(const std::string& axis, double min, double max);
  // SPEED: the axis's cruise speed (mm/s or deg/s) for the moves that follow; StationError
  // (-222) beyond the station's fastest.
  void SetSpeed(const std::string& axis, double unit_per_s);

  void SetCurrent(double bias_ma);  // 0 = IRED off
  double MeasureCurrent();          // mA, as measured by the source (noisy)
  double current_setpoint_ma() const { return current_ma_; }

  // Programs (when the settings changed) and starts a pulse train: `count` rising edges
  // `period_us` apart, each `width_us` wide. One FIRE exchange when the train is the last one's
  // (a bracket's frames): the pulse counter is not read here (Pulses() does), which saves a
  // round trip per frame.
  void Trigger(int count, double width_us, double period_us);
  PulseCounter Pulses();
  // Polls until the running train is done; returns the pulse total.
  std::uint64_t WaitTriggerDone();

  void Stop();        // controlled stop of motion and trigger; waits until the axes stand still
  void EStop();       // immediate stop, IRED off; the station stays in ESTOP
  void ClearEStop();  // leaves ESTOP (unhomed)
  std::vector<StationErrorEntry> DrainErrors();  // reads SYST:ERR? until "0,No error"

  // One request with retries; returns the OK payload, throws StationError on ERR.
  std::string Command(std::string_view command);
  // One request with retries; returns the reply (OK or ERR). Throws LinkError.
  Reply Exchange(std::string_view command);

  const std::string& boot_id() const { return boot_id_; }
  bool homed() const { return homed_; }
  const ClientStats& stats() const { return stats_; }
  const ClientOptions& options() const { return options_; }

 private:
  void WaitMotionDone(const char* what, const long long* target_centi);
  std::string MoveCommand() const;
  [[noreturn]] void ThrowStuck(int attempts);
  void OnBootId(const std::string& seen);
  StationStatus StatusNoCheck();

  Transport& transport_;
  ClientOptions options_;
  int next_seq_ = 1;
  std::string boot_id_;
  // Trigger train settings last programmed (count, width us, period us) and under which boot id:
  // a bracket fires many one-pulse trains, and only the first needs COUN/WIDT/PER.
  std::string trigger_boot_id_;
  long long trigger_count_ = -1, trigger_width_us_ = -1, trigger_period_us_ = -1;
  StationPosition move_target_;
  long long move_centi_[3] = {0, 0, 0};
  bool homed_ = false;
  bool recovering_ = false;
  double current_ma_ = 0.0;
  ClientStats stats_;
};

}  // namespace irdist
