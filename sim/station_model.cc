#include "sim/station_model.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <map>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "base/check.h"
#include "sim/station_model_text.h"

namespace irdist::sim {

namespace {

constexpr int kSlide = 0;
constexpr int kPan = 1;
constexpr int kTilt = 2;
constexpr std::size_t kErrorQueueDepth = 16;
constexpr double kBootTimeS = 0.2;  // simulated time the station is deaf after a power-up

enum class State { kUnhomed, kHoming, kIdle, kMoving, kSettling, kEStop, kBooting };

const char* StateText(State s) {
  switch (s) {
    case State::kUnhomed: return "UNHOMED";
    case State::kHoming: return "HOMING";
    case State::kIdle: return "IDLE";
    case State::kMoving: return "MOVING";
    case State::kSettling: return "SETTLING";
    case State::kEStop: return "ESTOP";
    case State::kBooting: return "BOOTING";
  }
  return "UNKNOWN";
}

}  // namespace

// ------------------------------------------------------------------------------------------------
// The model proper: controller state and the command table, no I/O, no lock (the caller, e.g. the
// emulator's pty thread, serialises the calls).

struct StationModel::Impl {
  struct Axis {
    const AxisOptions* opt = nullptr;
    double pos = 0.0;          // physical position
    MotionProfile profile;     // current motion (from == to when at rest)
    double speed = 1.0;        // cruise speed (SPEED; the options' speed at power-up)
    bool moving = false;
  };

  StationEffects& effects;
  EmulatorOptions options;
  std::mt19937_64 rng;
  std::random_device entropy;

  // Controller state.
  State state = State::kBooting;
  State after_boot = State::kUnhomed;
  double boot_done_s = 0.0;
  std::string boot_id;
  std::array<Axis, 3> axes;
  std::array<std::pair<double, double>, 3> soft;  // soft limits per axis
  double settle_until_s = 0.0;
  bool homing_ok = true;
  long long current_centi_ma = 0;
  // Trigger output.
  long long trig_count = 1, trig_width_us = 1000, trig_period_us = 10000;
  long long trig_remaining = 0;
  double trig_next_s = 0.0;
  std::uint64_t pulses_total = 0;
  // Error queue (SYST:ERR?).
  std::deque<CommandError> errors;
  // Faults and counters.
  double reboot_at_s = -1.0;  // scheduled reboot (simulated time), < 0 none
  double reboot_after_move_s = -1.0;
  std::uint64_t reboots = 0;
  int moves_started = 0;  // accepted MOVEs to a new target, for fault_at_move
  long long link_watchdog_s = 0;      // SYST:WDOG: link lost after this long without a request
  double last_valid_request_s = 0.0;
  bool silent = false;    // fault "silent": no reply any more

  Impl(StationEffects& e, EmulatorOptions o) : effects(e), options(std::move(o)), rng(options.seed) {
    std::string why;
    IRDIST_CHECK(options.IsValid(&why), why);
    reboot_after_move_s = options.reboot_after_s;
    axes[kSlide].opt = &options.slide;
    axes[kPan].opt = &options.pan;
    axes[kTilt].opt = &options.tilt;
    for (Axis& a : axes) {
      a.pos = a.opt->power_on;
      a.profile = MotionProfile::Rest(a.pos, 0.0);
    }
  }

  // Axis i follows `profile` from its start on; the world keeps it as its exact trajectory.
  void Follow(int i, const MotionProfile& profile) {
    axes[i].profile = profile;
    effects.SetAxisMotion(static_cast<RigAxis>(i), profile);
  }

  // Every axis stops where it is at `now`, at once (no deceleration).
  void HaltAxes(double now) {
    for (int i = 0; i < 3; ++i) {
      Axis& a = axes[i];
      double v = 0.0;
      a.profile.At(now - a.profile.start_s, &a.pos, &v);
      Follow(i, MotionProfile::Rest(a.pos, now));
      a.moving = false;
    }
  }

  bool Chance(double p) { return p > 0.0 && std::uniform_real_distribution<double>(0, 1)(rng) < p; }

  void PushError(int code) {
    if (errors.size() >= kErrorQueueDepth) {
      errors.back() = ErrorFor(-350);
      return;
    }
    errors.push_back(ErrorFor(code));
  }

  // Power-up: new boot id, unhomed, IRED off, trigger idle, deaf for kBootTimeS.
  void PowerUp(double now) {
    link_watchdog_s = 0;  // power-on: no link watchdog
    std::uniform_int_distribution<std::uint32_t> dist;
    char id[16];
    std::snprintf(id, sizeof(id), "%08X", dist(entropy) ^ static_cast<std::uint32_t>(reboots));
    boot_id = id;
    for (int i = 0; i < 3; ++i) {
      axes[i].moving = false;
      axes[i].speed = axes[i].opt->speed;
      Follow(i, MotionProfile::Rest(axes[i].pos, now));
    }
    soft = {std::make_pair(options.slide.min, options.slide.max),
            std::make_pair(options.pan.min, options.pan.max),
            std::make_pair(options.tilt.min, options.tilt.max)};
    state = State::kBooting;
    after_boot = State::kUnhomed;
    boot_done_s = now + kBootTimeS;
    current_centi_ma = 0;
    effects.SetCurrent(0.0);
    trig_remaining = 0;
    pulses_total = 0;
    errors.clear();
    PushError(-500);
    reboot_at_s = -1.0;
    PublishPose();
    effects.PoweredUp();
  }

  // Immediate halt, IRED off, trigger aborted: the ESTOP command or the station's stop button.
  void EStop(double now) {
    HaltAxes(now);
    trig_remaining = 0;
    current_centi_ma = 0;
    effects.SetCurrent(0.0);
    state = State::kEStop;
  }

  // No valid request within SYST:WDOG seconds: IRED off, motion and trigger stopped, error 206.
  void OnLinkLost(double now) {
    link_watchdog_s = 0;
    current_centi_ma = 0;
    effects.SetCurrent(0.0);
    trig_remaining = 0;
    if (state == State::kMoving || state == State::kHoming || state == State::kSettling) {
      HaltAxes(now);
      state = homing_ok ? State::kIdle : State::kUnhomed;
    }
    PushError(206);
  }

  void Reboot(double now) {
    // Power loss: the axes stop where they are (no controlled deceleration).
    for (Axis& a : axes) {
      double v = 0.0;
      a.profile.At(now - a.profile.start_s, &a.pos, &v);
    }
    ++reboots;
    PowerUp(now);
  }

  bool AnyMoving() const {
    return state == State::kMoving || state == State::kHoming || state == State::kSettling;
  }

  void PublishPose() {
    effects.SetPose(axes[kSlide].pos, axes[kPan].pos, axes[kTilt].pos, AnyMoving());
  }

  int StuckAxis() const {
    if (options.stuck_axis == "slide") return kSlide;
    if (options.stuck_axis == "pan") return kPan;
    if (options.stuck_axis == "tilt") return kTilt;
    return -1;
  }

  // Starts profiles towards `target` (physical units) on all axes.
  void StartMotion(const std::array<double, 3>& target, double speed_factor, double now) {
    const int stuck = StuckAxis();
    for (int i = 0; i < 3; ++i) {
      Axis& a = axes[i];
      double v = 0.0;
      a.profile.At(now - a.profile.start_s, &a.pos, &v);
      const double to = (i == stuck) ? a.pos : target[i];
      Follow(i, MotionProfile::Make(a.pos, to, now, 0.0, a.speed * speed_factor,
                                    a.opt->accel));
      a.moving = std::fabs(to - a.pos) > 0.0;
    }
  }

  // Advances motion, settling, homing, booting, scheduled reboots and the trigger train to `now`.
  void Advance(double now) {
    if (reboot_at_s >= 0.0 && now >= reboot_at_s) Reboot(reboot_at_s);
    if (link_watchdog_s > 0 && now - last_valid_request_s > link_watchdog_s) OnLinkLost(now);
    if (state == State::kBooting) {
      if (now >= boot_done_s) state = after_boot;
      else return;
    }
    if (state == State::kMoving || state == State::kHoming) {
      bool done = true;
      double settle = 0.0;
      for (Axis& a : axes) {
        double v = 0.0;
        a.profile.At(now - a.profile.start_s, &a.pos, &v);
        if (now < a.profile.EndS()) done = false;
        if (a.moving) settle = std::max(settle, a.opt->settle_s);
      }
      if (done) {
        double end_s = 0.0;
        for (Axis& a : axes) end_s = std::max(end_s, a.profile.EndS());
        if (state == State::kHoming) {
          const int stuck = StuckAxis();
          homing_ok = true;
          for (int i = 0; i < 3; ++i) {
            if (std::fabs(axes[i].pos - axes[i].opt->home) > 1e-9) homing_ok = false;
          }
          if (!homing_ok && stuck >= 0) PushError(204);
        }
        settle_until_s = end_s + settle;
        state = State::kSettling;
      }
    }
    if (state == State::kSettling && now >= settle_until_s) {
      for (Axis& a : axes) a.moving = false;
      state = homing_ok ? State::kIdle : State::kUnhomed;
    }
    PublishPose();
    // Trigger train, in simulated time. A pulse fired late (the host did not run this loop in
    // time) pushes the rest of the train back: pulses are never closer than the period, as on a
    // hardware timer, so a camera never sees two pulses inside one frame time.
    if (trig_remaining > 0 && now >= trig_next_s) {
      ++pulses_total;
      --trig_remaining;
      trig_next_s = now + static_cast<double>(trig_period_us) * 1e-6;
      if (!Chance(options.missed_pulse_rate)) effects.FireTrigger();
    }
  }

  // Position as reported: during settling a small decaying ringing around the target.
  long long Reported(int i, double now) const {
    double p = axes[i].pos;
    if (state == State::kSettling && axes[i].moving && axes[i].opt->settle_s > 0.0) {
      const double left = std::max(0.0, settle_until_s - now) / axes[i].opt->settle_s;
      p += 0.05 * left * std::sin(now * 2.0 * 3.14159265358979 * 40.0);
    }
    return Centi(p);
  }

  using Request = StationRequest;
  using Handler = std::string (Impl::*)(const Request&);

  // Queues the error and returns its ERR reply.
  std::string Fail(int code) {
    PushError(code);
    const CommandError e = ErrorFor(code);
    return "ERR " + std::to_string(code) + ",\"" + e.message + "\"";
  }

  // The command table of docs/station-protocol.md, section 5.
  static const std::map<std::string, Handler>& Commands() {
    static const std::map<std::string, Handler> table = {
        {"*IDN?", &Impl::CmdIdnQuery},
        {"*CLS", &Impl::CmdCls},
        {"SYST:ERR?", &Impl::CmdSystErrQuery},
        {"STAT?", &Impl::CmdStatQuery},
        {"POS?", &Impl::CmdPosQuery},
        {"LIM?", &Impl::CmdLimQuery},
        {"LIM", &Impl::CmdLim},
        {"SPEED?", &Impl::CmdSpeedQuery},
        {"SPEED", &Impl::CmdSpeed},
        {"HOME", &Impl::CmdHome},
        {"MOVE", &Impl::CmdMove},
        {"STOP", &Impl::CmdStop},
        {"ESTOP", &Impl::CmdEstop},
        {"ESTOP:CLR", &Impl::CmdEstopClr},
        {"SOUR:CURR", &Impl::CmdSourCurr},
        {"SOUR:CURR?", &Impl::CmdSourCurrQuery},
        {"MEAS:CURR?", &Impl::CmdMeasCurrQuery},
        {"TRIG:COUN", &Impl::CmdTrigSetting},
        {"TRIG:WIDT", &Impl::CmdTrigSetting},
        {"TRIG:PER", &Impl::CmdTrigSetting},
        {"TRIG?", &Impl::CmdTrigQuery},
        {"TRIG:FIRE", &Impl::CmdTrigFire},
        {"TRIG:ABOR", &Impl::CmdTrigAbor},
        {"TRIG:PULS?", &Impl::CmdTrigPulsQuery},
        {"SYST:WDOG", &Impl::CmdSystWdog},
        {"SYST:WDOG?", &Impl::CmdSystWdogQuery},
    };
    return table;
  }

  // Executes one command (already unframed). Returns the reply body ("OK ..." or "ERR ...").
  std::string Execute(const std::string& command, double now) {
    const std::size_t space = command.find(' ');
    Request r;
    r.header = Upper(command.substr(0, space));
    r.args = SplitCommas(space == std::string::npos ? "" : command.substr(space + 1));
    r.now = now;
    const auto it = Commands().find(r.header);
    if (it == Commands().end()) return Fail(-113);
    return (this->*(it->second))(r);
  }

  std::string CmdIdnQuery(const Request& r) {
    if (int e = r.NoArgs()) return Fail(e);
    return "OK IRDIST,VSTATION,EMU0001,1.0," + boot_id;
  }

  std::string CmdCls(const Request& r) {
    if (int e = r.NoArgs()) return Fail(e);
    errors.clear();
    return "OK";
  }

  std::string CmdSystErrQuery(const Request& r) {
    if (int e = r.NoArgs()) return Fail(e);
    if (errors.empty()) return "OK 0,\"No error\"";
    const CommandError e = errors.front();
    errors.pop_front();
    return "OK " + std::to_string(e.code) + ",\"" + e.message + "\"";
  }

  std::string CmdStatQuery(const Request& r) {
    if (int e = r.NoArgs()) return Fail(e);
    return std::string("OK ") + StateText(state) + "," + boot_id;
  }

  std::string CmdPosQuery(const Request& r) {
    char buf[160];
    if (int e = r.NoArgs()) return Fail(e);
    std::snprintf(buf, sizeof(buf), "OK %lld,%lld,%lld", Reported(kSlide, r.now),
                  Reported(kPan, r.now), Reported(kTilt, r.now));
    return buf;
  }

  std::string CmdLimQuery(const Request& r) {
    char buf[160];
    if (int e = r.NoArgs()) return Fail(e);
    std::snprintf(buf, sizeof(buf), "OK %lld,%lld,%lld,%lld,%lld,%lld", Centi(soft[0].first),
                  Centi(soft[0].second), Centi(soft[1].first), Centi(soft[1].second),
                  Centi(soft[2].first), Centi(soft[2].second));
    return buf;
  }

  std::string CmdLim(const Request& r) {
    int i = -1;
    std::vector<long long> v;
    if (int e = r.AxisAndInts(2, &i, &v)) return Fail(e);
    if (v[0] >= v[1] || v[0] < Centi(axes[i].opt->min) || v[1] > Centi(axes[i].opt->max)) {
      return Fail(-222);
    }
    soft[i] = {v[0] / 100.0, v[1] / 100.0};
    return "OK";
  }

  // SPEED <axis>,<v>: the axis's cruise speed for the moves that follow, in 0.01 unit/s, within
  // [1, the axis's max_speed]. Power-up restores `speed`.
  std::string CmdSpeed(const Request& r) {
    int i = -1;
    std::vector<long long> v;
    if (int e = r.AxisAndInts(1, &i, &v)) return Fail(e);
    if (v[0] < 1 || v[0] > Centi(axes[i].opt->MaxSpeed())) return Fail(-222);
    axes[i].speed = v[0] / 100.0;  // a move under way keeps its profile
    return "OK";
  }

  std::string CmdSpeedQuery(const Request& r) {
    if (int e = r.NoArgs()) return Fail(e);
    return "OK " + CentiList({axes[kSlide].speed, axes[kPan].speed, axes[kTilt].speed});
  }

  std::string CmdHome(const Request& r) {
    if (int e = r.NoArgs()) return Fail(e);
    if (state == State::kEStop) return Fail(202);
    if (state == State::kMoving || state == State::kSettling) return Fail(-221);
    if (state == State::kHoming) return "OK";  // already homing: idempotent
    StartMotion({options.slide.home, options.pan.home, options.tilt.home},
                options.homing_speed_factor, r.now);
    state = State::kHoming;
    return "OK";
  }

  std::string CmdMove(const Request& r) {
    std::vector<long long> v;
    if (int e = r.Ints(3, &v)) return Fail(e);
    if (state == State::kEStop) return Fail(202);
    if (state == State::kUnhomed || state == State::kHoming) return Fail(201);
    for (int i = 0; i < 3; ++i) {
      if (v[i] < Centi(soft[i].first) || v[i] > Centi(soft[i].second)) return Fail(-222);
    }
    const std::array<double, 3> target = {v[0] / 100.0, v[1] / 100.0, v[2] / 100.0};
    if (state == State::kMoving || state == State::kSettling) {
      bool same = true;
      for (int i = 0; i < 3; ++i) same = same && Centi(axes[i].profile.to) == v[i];
      return same ? "OK" : Fail(-221);  // same target again: idempotent
    }
    if (++moves_started == options.fault_at_move && options.fault == "refuse") {
      return Fail(-222);
    }
    StartMotion(target, 1.0, r.now);
    state = State::kMoving;
    homing_ok = true;
    if (moves_started == options.fault_at_move) {
      if (options.fault == "estop") EStop(r.now);
      if (options.fault == "silent") silent = true;
    }
    if (reboot_after_move_s >= 0.0) {
      reboot_at_s = r.now + reboot_after_move_s;
      reboot_after_move_s = -1.0;
    }
    return "OK";
  }

  std::string CmdStop(const Request& r) {
    if (int e = r.NoArgs()) return Fail(e);
    trig_remaining = 0;
    if (state == State::kMoving || state == State::kHoming) {
      const bool homing = state == State::kHoming;
      for (int i = 0; i < 3; ++i) {
        Axis& a = axes[i];
        double speed = 0.0;
        a.profile.At(r.now - a.profile.start_s, &a.pos, &speed);
        const double dir = a.profile.to >= a.profile.from ? 1.0 : -1.0;
        const double stop_at = a.pos + dir * speed * speed / (2.0 * a.opt->accel);
        Follow(i, MotionProfile::Make(a.pos, stop_at, r.now, speed, speed, a.opt->accel));
      }
      state = State::kMoving;
      homing_ok = !homing;
    }
    return "OK";
  }

  std::string CmdEstop(const Request& r) {
    if (int e = r.NoArgs()) return Fail(e);
    EStop(r.now);
    return "OK";
  }

  std::string CmdEstopClr(const Request& r) {
    if (int e = r.NoArgs()) return Fail(e);
    if (state == State::kEStop) state = State::kUnhomed;
    return "OK";
  }

  std::string CmdSourCurr(const Request& r) {
    std::vector<long long> v;
    if (int e = r.Ints(1, &v)) return Fail(e);
    // Turning the IRED off is always possible, also in ESTOP (docs/station-protocol.md).
    const bool off_allowed = v[0] == 0 && !options.refuse_current_off_in_estop;
    if (state == State::kEStop && !off_allowed) return Fail(202);
    if (v[0] < 0 || v[0] > Centi(options.max_current_ma)) return Fail(-222);
    if (v[0] != current_centi_ma) {
      current_centi_ma = v[0];
      effects.SetCurrent(options.open_circuit ? 0.0 : v[0] / 100.0);
    }
    return "OK";
  }

  std::string CmdSourCurrQuery(const Request& r) {
    if (int e = r.NoArgs()) return Fail(e);
    return "OK " + std::to_string(current_centi_ma);
  }

  std::string CmdMeasCurrQuery(const Request& r) {
    if (int e = r.NoArgs()) return Fail(e);
    // An open IRED circuit: the source's output cannot drive any current.
    double ma = options.open_circuit ? 0.0 : current_centi_ma / 100.0;
    if (current_centi_ma > 0 && options.current_noise_ma > 0 && !options.open_circuit) {
      ma += std::normal_distribution<double>(0.0, options.current_noise_ma)(rng);
    }
    return "OK " + std::to_string(std::max(0LL, Centi(ma)));
  }

  std::string CmdTrigSetting(const Request& r) {
    std::vector<long long> v;
    if (int e = r.Ints(1, &v)) return Fail(e);
    if (trig_remaining > 0) return Fail(-221);
    if (r.header == "TRIG:COUN") {
      if (v[0] < 1 || v[0] > static_cast<long long>(options.max_trigger_count)) return Fail(-222);
      trig_count = v[0];
    } else if (r.header == "TRIG:WIDT") {
      if (v[0] < std::llround(options.min_trigger_width_us) || v[0] >= trig_period_us) {
        return Fail(-222);
      }
      trig_width_us = v[0];
    } else {
      if (v[0] < std::llround(options.min_trigger_period_us) || v[0] <= trig_width_us) {
        return Fail(-222);
      }
      trig_period_us = v[0];
    }
    return "OK";
  }

  std::string CmdTrigQuery(const Request& r) {
    char buf[160];
    if (int e = r.NoArgs()) return Fail(e);
    std::snprintf(buf, sizeof(buf), "OK %lld,%lld,%lld", trig_count, trig_width_us,
                  trig_period_us);
    return buf;
  }

  std::string CmdTrigFire(const Request& r) {
    if (int e = r.NoArgs()) return Fail(e);
    if (state == State::kEStop) return Fail(202);
    if (trig_remaining > 0) return Fail(-221);
    trig_remaining = trig_count;
    trig_next_s = r.now;
    return "OK";
  }

  std::string CmdTrigAbor(const Request& r) {
    if (int e = r.NoArgs()) return Fail(e);
    trig_remaining = 0;
    return "OK";
  }

  std::string CmdSystWdog(const Request& r) {
    std::vector<long long> v;
    if (int e = r.Ints(1, &v)) return Fail(e);
    if (v[0] < 0 || v[0] > 3600) return Fail(-222);
    link_watchdog_s = v[0];
    return "OK";
  }

  std::string CmdSystWdogQuery(const Request& r) {
    if (int e = r.NoArgs()) return Fail(e);
    return "OK " + std::to_string(link_watchdog_s);
  }

  std::string CmdTrigPulsQuery(const Request& r) {
    if (int e = r.NoArgs()) return Fail(e);
    return "OK " + std::to_string(pulses_total) + "," + std::to_string(trig_remaining);
  }
};

StationModel::StationModel(StationEffects& effects, EmulatorOptions options)
    : impl_(std::make_unique<Impl>(effects, std::move(options))) {}

StationModel::~StationModel() = default;

void StationModel::PowerOn(double now_s) {
  impl_->PowerUp(now_s);
  impl_->boot_done_s = now_s;  // the first power-up happened before anyone listened
  impl_->Advance(now_s);       // out of BOOTING at once
}
std::string StationModel::Execute(const std::string& command, double now_s) {
  return impl_->Execute(command, now_s);
}
void StationModel::Advance(double now_s) { impl_->Advance(now_s); }
void StationModel::NoteValidRequest(double now_s) { impl_->last_valid_request_s = now_s; }
void StationModel::PushError(int code) { impl_->PushError(code); }
void StationModel::Reboot(double now_s) { impl_->Reboot(now_s); }
void StationModel::PressEmergencyStop(double now_s) { impl_->EStop(now_s); }
void StationModel::RebootDuringNextMove(double after_s) {
  IRDIST_CHECK(after_s >= 0.0, "after_s ", after_s);
  impl_->reboot_after_move_s = after_s;
}
EmulatorOptions& StationModel::options() { return impl_->options; }
bool StationModel::Booting() const { return impl_->state == State::kBooting; }
bool StationModel::Silent() const { return impl_->silent; }
std::optional<double> StationModel::NextPulseS() const {
  if (impl_->trig_remaining <= 0) return std::nullopt;
  return impl_->trig_next_s;
}
std::string StationModel::StateName() const { return StateText(impl_->state); }
std::string StationModel::BootId() const { return impl_->boot_id; }
std::uint64_t StationModel::Reboots() const { return impl_->reboots; }
std::mt19937_64& StationModel::Random() { return impl_->rng; }
bool StationModel::Chance(double p) { return impl_->Chance(p); }

}  // namespace irdist::sim
