// Ctrl-C: SIGINT/SIGTERM set the stop flag while a SignalGuard lives, and the previous handlers
// come back after it.
#include "app/inputs/stop_signal.h"

#include <gtest/gtest.h>
#include <signal.h>

#include <atomic>

namespace irdist {
namespace {

std::atomic<int> previous_calls{0};
extern "C" void PreviousHandler(int) { previous_calls.fetch_add(1); }

TEST(SignalGuardTest, SigintAndSigtermRequestAStopThenTheOldHandlersReturn) {
  struct sigaction old_int {
  }, old_term{}, mine{};
  mine.sa_handler = PreviousHandler;
  sigemptyset(&mine.sa_mask);
  sigaction(SIGINT, &mine, &old_int);
  sigaction(SIGTERM, &mine, &old_term);
  {
    SignalGuard guard;
    EXPECT_FALSE(StopRequested().load());
    raise(SIGINT);
    EXPECT_TRUE(StopRequested().load());
    StopRequested().store(false);
    raise(SIGTERM);
    EXPECT_TRUE(StopRequested().load());
    EXPECT_EQ(previous_calls.load(), 0);
  }
  raise(SIGINT);
  EXPECT_EQ(previous_calls.load(), 1);
  {
    SignalGuard guard;  // a new run starts with the flag cleared
    EXPECT_FALSE(StopRequested().load());
  }
  sigaction(SIGINT, &old_int, nullptr);
  sigaction(SIGTERM, &old_term, nullptr);
}

}  // namespace
}  // namespace irdist
