#include "sim/trajectory_file.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include "base/input_error.h"
#include "base/utc_time.h"
#include "sim/world.h"

// The trajectory's CSV file: written as the profiles start, read back into the same trajectory;
// a damaged file refused at its line.

namespace irdist::sim {
namespace {

std::string TempPath(const std::string& name) {
  const char* tmp = std::getenv("TMPDIR");
  return std::string(tmp != nullptr ? tmp : "/tmp") + "/irdist-" + name + "-" +
         std::to_string(::getpid()) + ".csv";
}

std::string Slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// The rows of a logged move 1500 -> 3000 mm (0.5 m/s, 1 m/s^2) at t = 2 s, pan and tilt at rest.
void LogAMove(World& world) {
  world.SetAxisMotion(RigAxis::kSlide, MotionProfile::Rest(1500.0, 0.0));
  world.SetAxisMotion(RigAxis::kPan, MotionProfile::Rest(0.0, 0.0));
  world.SetAxisMotion(RigAxis::kTilt, MotionProfile::Rest(0.0, 0.0));
  world.SetAxisMotion(RigAxis::kSlide, MotionProfile::Make(1500.0, 3000.0, 2.0, 0.0, 500.0, 1e3));
}

TEST(TrajectoryFile, ReadsBackTheExactTrajectoryWithTimesInNsAndUtc) {
  const std::string path = TempPath("trajectory");
  ::unlink(path.c_str());
  World world(10.0);
  LogAMove(world);  // before the log starts: the profiles in force are its first rows
  world.LogTrajectory(path);
  world.SetAxisMotion(RigAxis::kPan, MotionProfile::Make(0.0, 20.0, 2.5, 0.0, 30.0, 60.0));
  EXPECT_EQ(world.TrajectoryLogPath(), path);
  EXPECT_EQ(world.TrajectoryLogError(), "");
  const std::string text = Slurp(path);
  EXPECT_EQ(text.substr(0, text.find('\n')), TrajectoryCsvHeader());
  // One row per profile in force or started: slide (the move), pan (rest), tilt, pan (the move).
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 5);
  EXPECT_NE(text.find("\nslide,mm,2000000000,"), std::string::npos) << text;
  // UTC: the wall clock at the world's start plus the host time (2 s simulated at 10x = 0.2 s).
  const std::int64_t utc_ns = world.clock().UtcNs(2.0);
  EXPECT_NE(text.find("2000000000," + FormatUtcIso8601(utc_ns)), std::string::npos) << text;
  EXPECT_NEAR(static_cast<double>(utc_ns - world.clock().UtcNs(0.0)), 0.2e9, 1.0);

  const Trajectory read = ReadTrajectoryFile(path);
  for (double t : {0.0, 2.0, 2.3, 2.6, 4.0, 5.0, 5.4, 6.0}) {
    const TrajectoryPoint want = world.TruthAt(t);
    const TrajectoryPoint got = read.At(t);
    ASSERT_TRUE(got.known);
    EXPECT_NEAR(got.slide_mm, want.slide_mm, 1e-9) << t;
    EXPECT_NEAR(got.slide_mm_s, want.slide_mm_s, 1e-9) << t;
    EXPECT_NEAR(got.pan_deg, want.pan_deg, 1e-9) << t;
    EXPECT_NEAR(got.pan_deg_s, want.pan_deg_s, 1e-9) << t;
  }
  ::unlink(path.c_str());
}

TEST(TrajectoryFile, RefusesAnExistingFileOrLink) {
  const std::string path = TempPath("taken");
  { std::ofstream(path) << "someone's file\n"; }
  World world;
  EXPECT_THROW(world.LogTrajectory(path), TrajectoryFileError);
  EXPECT_EQ(Slurp(path), "someone's file\n");
  ::unlink(path.c_str());
}

// Each damage is refused at its line, naming what is wrong.
TEST(TrajectoryFile, RefusesADamagedRowAtItsLine) {
  World world;
  const auto utc = [&world](double s) { return world.clock().UtcNs(s); };
  const std::string good =
      TrajectoryCsvRow(RigAxis::kSlide, MotionProfile::Make(1500, 3000, 2, 0, 500, 1e3), utc);
  const std::string header = TrajectoryCsvHeader() + "\n";
  const auto expect_refused = [&](const std::string& text, int line, const std::string& what) {
    try {
      ParseTrajectoryCsv(text, "t.csv");
      ADD_FAILURE() << "accepted: " << text;
    } catch (const InputError& e) {
      EXPECT_EQ(e.Line(), line) << e.what();
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  expect_refused("axis,when\n" + good + "\n", 1, "header");
  expect_refused(header + good + "\n" + "roll" + good.substr(5) + "\n", 3, "axis 'roll'");
  expect_refused(header + "slide,deg" + good.substr(8) + "\n", 2, "unit 'deg'");
  std::string negative = good;
  negative.replace(negative.rfind(','), std::string::npos, ",-1");
  expect_refused(header + negative + "\n", 2, "decel_s must be >= 0");
  expect_refused(header + good + ",7\n", 2, "15 fields");
  expect_refused(header + "slide, mm" + good.substr(8) + "\n", 2, "space");
  const std::string earlier =
      TrajectoryCsvRow(RigAxis::kSlide, MotionProfile::Rest(1500, 1.0), utc);
  expect_refused(header + good + "\n" + earlier + "\n", 3, "back in time");
  // A row still being written (no newline yet) is not read.
  EXPECT_EQ(ParseTrajectoryCsv(header + good + "\nslide,mm,12", "t.csv")
                .Profiles(RigAxis::kSlide)
                .size(),
            1u);
}

}  // namespace
}  // namespace irdist::sim
