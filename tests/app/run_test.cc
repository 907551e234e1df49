// The run's signal handling: SIGINT/SIGTERM set the stop flag while a SignalGuard lives, and the
// previous handlers come back after it.
#include "app/run.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "app/command_args.h"

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

// plan --suggest --from: a summary whose best_dt_ms no exposure can hold, or a FIFO, is refused
// before the probe sweep (nothing is started, no probe folder is made); it was checked after it.
TEST(RunSuggestTest, ABadFromIsRefusedBeforeTheProbeSweep) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("irdist_suggest_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "summary.yaml") << "best_dt_ms: 1e308\n";
  ASSERT_EQ(::mkfifo((dir / "fifo.yaml").c_str(), 0600), 0);
  for (const char* from : {"summary.yaml", "fifo.yaml"}) {
    SCOPED_TRACE(from);
    PlanArgs args;
    args.recipe = std::string(IRDIST_SOURCE_DIR) + "/recipes/smoke-calibration.yaml";
    args.suggest = true;
    args.from_summary = (dir / from).string();
    args.out_dir = (dir / "probe").string();
    std::ostringstream out, err;
    try {
      RunSuggest(args, {out, err});
      ADD_FAILURE() << "accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(args.from_summary), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("(0, 100000]"), std::string::npos) << e.what();
    }
    EXPECT_FALSE(fs::exists(dir / "probe"));
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace irdist
