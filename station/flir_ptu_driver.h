#pragma once
// The FLIR PTU driver's class (station-internal: included by flir_ptu.cc, its commands, motion
// and registration, and flir_ptu_sync.cc, the line kept in step and the unit's resets), so that
// neither file grows past the house limit. Nothing outside station/ includes it.

#include <algorithm>
#include <chrono>
#include <climits>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "station/axes_motion.h"
#include "station/driver.h"
#include "station/flir_ptu_text.h"
#include "station/line_query.h"

namespace irdist::flir_ptu_internal {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

constexpr char kName[] = "flir_ptu";
constexpr double kArcsecPerDeg = 3600.0;
constexpr milliseconds kPollPeriod{10};
constexpr int kStillPolls = 15;  // polls standing still, away from the target: stopped short
constexpr milliseconds kQuietAfterVersion{200};  // SyncOnVersion: the line is quiet after V

struct PtuAxis {
  Axis axis = Axis::kPan;
  char letter = 'P';            // command prefix: P (pan) or T (tilt)
  double deg_per_position = 0;  // PR/TR (arc seconds) / 3600
  long long min_pos = 0, max_pos = 0;
  AxisSpeed speed;
  long long target = 0;
  bool has_target = false;
  long long speed_pos_s = 0;  // PS/TS as read at Identify (a power cycle restores defaults)
  long long upper_pos_s = 0, lower_pos_s = 0;  // PU/PL (TU/TL) speed bounds; 0: not read
};

using ptu_text::FirstNumber;
using ptu_text::IsLimitHit;
using ptu_text::IsRateCommand;

class FlirPtu : public AxesMotionDriver<PtuAxis> {
 public:
  FlirPtu(const DeviceSpec& spec, std::unique_ptr<Transport> link)
      : spec_(spec), link_(std::move(link)), query_(link_.get(), QueryOptions(spec)) {
    identity_.kind = kName;
    identity_.port = spec.port;
    identity_.vendor = "FLIR";
    timeout_ = query_.options().reply_timeout;
    attempts_ = query_.options().attempts;
    tolerance_ = static_cast<long long>(spec.Number("tolerance_positions", 0));
    home_timeout_ = milliseconds(static_cast<long long>(spec.Number("home_timeout_s", 120) * 1000));
    reset_wait_ = milliseconds(static_cast<long long>(spec.Number("reset_wait_s", 60) * 1000));
    for (const auto& [axis, address] : spec.axes) {
      PtuAxis a;
      a.axis = axis;
      a.letter = address == "pan" ? 'P' : 'T';
      axes_.push_back(a);
    }
  }

  DeviceIdentity Identify() override;
  MotionState State() override;
  void Home() override;
  void StartMove(const StationPosition& target) override;
  void WaitSettled(milliseconds timeout) override;
  void ReadPosition(StationPosition* position) override;
  void Stop() noexcept override;
  void SetSpeed(Axis axis, double unit_per_s) override;
  void CheckAlive() override;

 private:
  LineQueryOptions QueryOptions(const DeviceSpec& spec);
  ReplyVerdict Judge(const std::string& command, const std::string& line, std::string* body) const;
  LineRequest Request(const std::string& command, std::string* body) const;
  std::string Query(const std::string& command);
  double QueryNumber(const std::string& command);
  bool Command(const std::string& command, milliseconds wait);
  long long Position(const PtuAxis& a) {
    return std::llround(QueryNumber(std::string(1, a.letter) + "P"));
  }
  long long StablePosition(const PtuAxis& a);
  void ReadAxis(PtuAxis* a);
  void ApplySpeed(PtuAxis* a);
  void SendSpeed(PtuAxis* a, double deg_s, const std::string& fix);
  void MoveAxis(PtuAxis* a, long long position);
  void WaitAt(milliseconds timeout, const std::string& what);
  void TakePending(bool report_limit_hit);
  struct VersionSync {
    Clock::time_point deadline;
    int answered = 0, unanswered = 0;
    std::string heard;       // the last line before the version
    bool resetting = false;  // the unit's banner, "Initializing..." or an echo was heard
  };
  void SyncOnVersion();
  bool SyncStep(VersionSync* sync);
  void NotePowerUpText(const std::string& line) const;
  void NotePowerUp();
  void ConfirmStopped(milliseconds timeout);
  void Reidentify();
  bool IsVersion(const std::string& line) const;
  [[noreturn]] void LimitHit(const std::string& line) const;
  void ReadSpeedBounds(PtuAxis* a);
  [[noreturn]] void StoppedShort(const std::string& what, const std::vector<long long>& positions);
  std::string AxisText(const PtuAxis& a) const { return AxisName(a.axis); }
  [[noreturn]] void Fail(const std::string& code, const std::string& message,
                         const std::string& fix) const {
    throw DeviceError(identity_, code, message, fix);
  }
  // A link failure naming the driver and the rig entry ("flir_ptu 'head': ...") and the port.
  [[noreturn]] void LinkFail(const std::string& message, const std::string& fix) const {
    throw LinkError(std::string(kName) + " '" + spec_.name + "': " + message, spec_.port, fix);
  }

  DeviceSpec spec_;
  std::unique_ptr<Transport> link_;
  LineQuery query_;  // after link_: it writes and reads through it
  DeviceIdentity identity_;
  milliseconds timeout_{1000};
  milliseconds home_timeout_{120000};
  milliseconds reset_wait_{60000};  // a unit silent this long after a lost reply is gone
  int attempts_ = 3;
  std::string version_;       // the unit's V answer: the resynchronisation marker
  bool out_of_step_ = false;  // a reply was lost: resynchronise before the next command
  long long tolerance_ = 0;
  bool homed_ = false;
  bool moving_ = false;
  bool was_away_ = false;  // an axis stood or was seen away from 0 since the move began
  mutable bool power_up_seen_ = false;  // the unit's banner or "Initializing..." was read
  bool restarted_ = false;  // found reset: Home() identifies the unit again first
};

}  // namespace irdist::flir_ptu_internal
