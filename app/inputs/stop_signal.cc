#include "app/inputs/stop_signal.h"

#include <signal.h>

namespace irdist {

std::atomic<bool>& StopRequested() {
  static std::atomic<bool> stop{false};
  return stop;
}

namespace {

extern "C" void OnStopSignal(int) { StopRequested().store(true); }

}  // namespace

struct SignalGuard::Saved {
  struct sigaction interrupt {};
  struct sigaction terminate {};
};

SignalGuard::SignalGuard() : saved_(new Saved) {
  StopRequested().store(false);
  struct sigaction action {};
  action.sa_handler = OnStopSignal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;
  sigaction(SIGINT, &action, &saved_->interrupt);
  sigaction(SIGTERM, &action, &saved_->terminate);
}

SignalGuard::~SignalGuard() {
  sigaction(SIGINT, &saved_->interrupt, nullptr);
  sigaction(SIGTERM, &saved_->terminate, nullptr);
  delete saved_;
}

}  // namespace irdist
