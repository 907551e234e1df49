#pragma once
// Ctrl-C for the commands that run until stopped (calibrate, validate, measure, view, sim): while a
// SignalGuard lives, SIGINT and SIGTERM only set a flag that the command polls between poses,
// brackets or frames; it then finishes what is in flight and ends with exit code 130
// (InterruptedError, app/inputs/errors.h).

#include <atomic>

namespace irdist {

// Set by SIGINT/SIGTERM while a run's SignalGuard is alive; polled between poses.
std::atomic<bool>& StopRequested();

// Installs SIGINT/SIGTERM handlers that set StopRequested() (and clears it); restores the previous
// handlers when destroyed.
class SignalGuard {
 public:
  SignalGuard();
  ~SignalGuard();
  SignalGuard(const SignalGuard&) = delete;
  SignalGuard& operator=(const SignalGuard&) = delete;
  SignalGuard(SignalGuard&&) = delete;
  SignalGuard& operator=(SignalGuard&&) = delete;

 private:
  struct Saved;
  Saved* saved_;
};

}  // namespace irdist
