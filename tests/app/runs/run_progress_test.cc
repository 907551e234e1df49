// A live run's progress: nothing when quiet; off a terminal one line per pose with the plan's ETA
// until poses have been measured, then the measured rate's.
#include "app/runs/run_progress.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <sstream>
#include <string>

namespace irdist {
namespace {

TEST(RunProgress, QuietPrintsNothing) {
  std::ostringstream err;
  Progress progress(err, true, 4, 40.0);
  progress.Update(1, "d 1500 mm");
  progress.Finish();
  EXPECT_EQ(err.str(), "");
}

// Off a terminal (a log): one line per pose. The first update has no measured rate: the ETA is
// the plan's 10 s per pose for the 3 poses left.
TEST(RunProgress, OffATerminalOneLinePerPoseWithThePlansEta) {
  if (isatty(STDERR_FILENO) == 1) GTEST_SKIP() << "stderr is a terminal: the bar is drawn";
  std::ostringstream err;
  Progress progress(err, false, 4, 40.0);
  progress.Update(1, "d 1500 mm, theta 0 deg, 500 mA");
  EXPECT_EQ(err.str().rfind("pose 1/4 (d 1500 mm, theta 0 deg, 500 mA), elapsed 0.0 s, ETA 30.0 s\n",
                            0),
            0u)
      << err.str();
  // The next pose comes at once: measured at ~0 s per pose, weighted 1/5 against the plan's.
  progress.Update(2, "d 2000 mm");
  EXPECT_NE(err.str().find("pose 2/4 (d 2000 mm), elapsed 0.0 s, ETA 16.0 s\n"), std::string::npos)
      << err.str();
  const std::string before = err.str();
  progress.Finish();  // no bar line to end
  EXPECT_EQ(err.str(), before);
}

}  // namespace
}  // namespace irdist
