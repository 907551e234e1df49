// `irdist measure --track` end to end on the virtual rig , through the
// built binary: a small calibration first (at time scale 50), then tracking a static IRED at time
// scale 1 (every line mode "track", no frame lost, every frame between two lines counted as
// skipped, the estimates within their standard errors of the pose, the per-frame scatter against
// the reported standard error and the one-frame Cramer-Rao bound, the calibration health pooled
// and quiet, the filter at rest), the interleaved bracket agreeing with the
// track, Ctrl-C and a reader that goes away (| head) ending it cleanly, and its refusals.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "sim/rig_physics.h"
#include "tests/integration/measure_helpers.h"
#include "tests/integration/one_frame_bound.h"
#include "tests/integration/run_helpers.h"
#include "tests/loopback_gvcp.h"

namespace irdist {
namespace {

using testing::JsonLines;
using testing::ReadAll;
using testing::RunIrdist;
using testing::WriteAll;

class MeasureTrack : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new std::string(testing::ScratchDir("measure-track"));
    WriteAll(*dir_ + "/calibration.yaml", testing::SmallCalibrationRecipe("track-calibration"));
    testing::LoopbackGvcpLock lock;
    calibrate_code_ = RunIrdist({"calibrate", *dir_ + "/calibration.yaml", "--out", *dir_ + "/cal",
                                 "--time-scale", "50", "--quiet"},
                                *dir_ + "/calibrate.log", &calibrate_output_);
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  void SetUp() override { ASSERT_EQ(calibrate_code_, 0) << calibrate_output_; }

  static std::string Model() { return *dir_ + "/cal/model.yaml"; }
  // measure --track with the model at time scale 1 (the camera's real rate) and `extra`.
  static std::vector<std::string> TrackArgs(std::vector<std::string> extra) {
    std::vector<std::string> args = {"measure", "--model", Model(), "--track", "--time-scale", "1"};
    args.insert(args.end(), extra.begin(), extra.end());
    return args;
  }
  static int Track(const std::string& name, std::vector<std::string> extra, std::string* output) {
    testing::LoopbackGvcpLock lock;
    return RunIrdist(TrackArgs(std::move(extra)), *dir_ + "/" + name + ".log", output);
  }

  static std::string* dir_;
  static int calibrate_code_;
  static std::string calibrate_output_;
};

std::string* MeasureTrack::dir_ = nullptr;
int MeasureTrack::calibrate_code_ = -1;
std::string MeasureTrack::calibrate_output_;

// The calibration health of a track line pools the own blurs of the frames before it (the first
// line's: its own): the blob fit's figure on every line, and a static IRED under its own
// calibration is no focus change (one false flag allowed).
void ExpectHealthPooledAndQuiet(const std::vector<YAML::Node>& lines, const std::string& output) {
  int pooled = 0, flagged = 0;
  for (const YAML::Node& j : lines) {
    if (j["health"].IsMap() && j["health"]["figure"].as<std::string>() == "blob_fit") {
      ++pooled;
      flagged += j["health"]["status"].as<std::string>() != "ok";
    }
  }
  std::printf("static: health pooled on %d of %zu lines, flagged on %d\n", pooled, lines.size(),
              flagged);
  EXPECT_EQ(pooled, static_cast<int>(lines.size())) << output;
  EXPECT_LE(flagged, 1) << output;
}

// The scatter `sd_mm` of `frames` frames of a static IRED at 2000 mm, pan 10 deg (8 ms at 490 mA,
// their reported standard errors' rms `rms_se_mm`) against the one-frame Cramer-Rao bound: the goal
// is 1.3; asserted with 3 of the ratio's sampling errors (9% at n = 60).
void ExpectScatterNearTheOneFrameBound(double sd_mm, double rms_se_mm, std::size_t frames) {
  const double bound_mm = testing::OneFrameBoundMm(
      sim::LoadRigPhysics(std::string(IRDIST_SOURCE_DIR) + "/recipes/rigs/virtual.yaml"), 2000.0,
      10.0, 8.0, 490.0);
  std::printf(
      "static: sd %.3f mm over %zu frames, one-frame bound %.3f mm (ratio %.3f), rms se "
      "%.3f mm\n",
      sd_mm, frames, bound_mm, sd_mm / bound_mm, rms_se_mm);
  EXPECT_LT(sd_mm / bound_mm, 1.3 * (1.0 + 3.0 * 0.092))
      << "sd " << sd_mm << " mm, one-frame bound " << bound_mm << " mm";
}

// A static IRED at 2000 mm, pan 10 deg: 60 frames.
TEST_F(MeasureTrack, StaticIredEveryFrameAccountedForAndWithinItsErrors) {
  std::string output;
  ASSERT_EQ(Track("static", {"--at", "2000,10,0,490", "--count", "60", "--json"}, &output), 0)
      << output;
  EXPECT_NE(output.find("track: triggered"), std::string::npos) << output;  // the header
  const std::vector<YAML::Node> lines = JsonLines(output);
  ASSERT_EQ(lines.size(), 60u) << output;
  std::int64_t previous = -1, previous_skipped = 0;
  double sum = 0.0, sum2 = 0.0, se2 = 0.0;
  for (const YAML::Node& j : lines) {
    ASSERT_EQ(j["mode"].as<std::string>(), "track") << output;
    EXPECT_EQ(j["acquisition"].as<std::string>(), "triggered");
    EXPECT_NEAR(j["exposure_ms"].as<double>(), 8.0, 1e-9);  // the model's reference exposure
    // Frames in order, none twice; every frame between two lines counted as skipped.
    const std::int64_t frame = j["frame"].as<std::int64_t>();
    const std::int64_t skipped = j["counters"]["skipped"].as<std::int64_t>();
    if (previous >= 0) {
      EXPECT_EQ(frame - previous - 1, skipped - previous_skipped) << output;
    }
    EXPECT_GT(frame, previous);
    previous = frame;
    previous_skipped = skipped;
    EXPECT_EQ(j["counters"]["lost"].as<int>(), 0) << output;
    EXPECT_EQ(j["counters"]["wrong_exposure"].as<int>(), 0) << output;
    EXPECT_FALSE(j["utc_time"].IsNull());
    EXPECT_FALSE(j["camera_timestamp_ns"].IsNull());
    ASSERT_TRUE(j["ok"].as<bool>()) << output;
    const double d = j["d_mm"].as<double>(), se = j["d_se_mm"].as<double>();
    ASSERT_GT(se, 0.0);
    // The truth: the emitter at 2000 mm on the axis; a few standard errors and the calibration's
    // own relative error (0.5%: the small calibration's geometric fit, 3 distances).
    EXPECT_NEAR(d, 2000.0, 4.0 * se + 0.005 * 2000.0) << output;
    EXPECT_NEAR(j["theta_deg"].as<double>(), 10.0, 2.0);
    EXPECT_TRUE(j["track"].IsMap()) << output;
    sum += d;
    sum2 += d * d;
    se2 += se * se;
  }
  const double n = static_cast<double>(lines.size());
  const double sd = std::sqrt((sum2 - sum * sum / n) / (n - 1.0));
  const double rms_se = std::sqrt(se2 / n);
  // The reported se is the calibration's one-frame noise carried to the track's exposure: the
  // scatter of 60 frames matches it, 1.6 lying 4 of the ratio's sampling errors (~10% at n = 60)
  // above the 1.13 observed and well below the unscaled noise's 1.96 (8 ms against 33 ms).
  EXPECT_GT(sd / rms_se, 0.7) << "sd " << sd << " se " << rms_se;
  EXPECT_LT(sd / rms_se, 1.6) << "sd " << sd << " se " << rms_se;
  ExpectScatterNearTheOneFrameBound(sd, rms_se, lines.size());
  ExpectHealthPooledAndQuiet(lines, output);
  const YAML::Node last = lines.back()["track"];
  // The static IRED's velocity within 4.5 se of zero, since at 3 se it would fail 0.27% of runs.
  EXPECT_LT(std::abs(last["v_mm_per_s"].as<double>()), 4.5 * last["v_se_mm_per_s"].as<double>())
      << output;
  EXPECT_LT(last["d_se_mm"].as<double>(), rms_se) << output;  // the track averages frames
  EXPECT_NE(output.find("Tracked 60 frames"), std::string::npos) << output;
}

// A bracket every 0.5 s among the frames: mode "bracket", a check that agrees with the track.
TEST_F(MeasureTrack, InterleavedBracketAppearsAndAgreesWithTheTrack) {
  std::string output;
  ASSERT_EQ(Track("check",
                  {"--at", "2000,0,0,490", "--check-every", "0.5", "--duration", "2.5", "--json"},
                  &output),
            0)
      << output;
  int brackets = 0, frames = 0;
  for (const YAML::Node& j : JsonLines(output)) {
    if (j["mode"].as<std::string>() == "track") {
      ++frames;
      continue;
    }
    ASSERT_EQ(j["mode"].as<std::string>(), "bracket") << output;
    ++brackets;
    EXPECT_TRUE(j["frame"].IsNull());
    ASSERT_TRUE(j["ok"].as<bool>()) << output;
    ASSERT_TRUE(j["check"].IsMap()) << output;
    EXPECT_TRUE(j["check"]["agree"].as<bool>()) << output;
    EXPECT_NEAR(j["check"]["track_d_mm"].as<double>(), j["d_mm"].as<double>(), 0.01 * 2000.0);
    EXPECT_TRUE(j["motion"].IsMap());  // the bracket's own checks, as measure's
  }
  EXPECT_GE(brackets, 2) << output;
  EXPECT_GE(frames, 10) << output;
  EXPECT_NE(output.find("bracket checks: "), std::string::npos) << output;
  EXPECT_EQ(output.find("disagrees with the track"), std::string::npos) << output;
}

TEST_F(MeasureTrack, CtrlCEndsCleanlyWithASummary) {
  testing::LoopbackGvcpLock lock;
  const std::string log = *dir_ + "/sigint.log";
  testing::Child child(TrackArgs({"--at", "2000,0,0,490"}), log);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  // The rig's and --at's lines, the header, then frames: SIGINT after a few frames.
  while (ReadAll(log).find("track #") == std::string::npos && testing::CountLines(log) < 30 &&
         child.Running() && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  child.Signal(SIGINT);
  EXPECT_EQ(child.Wait(std::chrono::seconds(30)), 0) << ReadAll(log);
  const std::string output = ReadAll(log);
  EXPECT_NE(output.find("Tracked "), std::string::npos) << output;
  EXPECT_NE(output.find("latency (frame arrival to estimate): median"), std::string::npos)
      << output;
}

TEST_F(MeasureTrack, JsonReaderThatGoesAwayEndsItCleanly) {
  const std::string log = *dir_ + "/head.log";
  testing::LoopbackGvcpLock lock;
  std::vector<std::string> lines;
  const int status =
      testing::ReadLinesThenGoAway(TrackArgs({"--at", "2000,0,0,490", "--json"}), 3, log, &lines);
  ASSERT_EQ(lines.size(), 3u) << ReadAll(log);
  ASSERT_TRUE(WIFEXITED(status)) << "killed by signal " << WTERMSIG(status) << "\n" << ReadAll(log);
  EXPECT_EQ(WEXITSTATUS(status), 0) << ReadAll(log);
  const std::string err = ReadAll(log);
  EXPECT_NE(err.find("Tracked "), std::string::npos) << err;
  EXPECT_NE(err.find("Stopped: stdout was closed"), std::string::npos) << err;
  for (const std::string& line : lines) {
    EXPECT_EQ(YAML::Load(line)["mode"].as<std::string>(), "track") << line;
  }
}

// An exposure outside the calibrated ones (8 ms and 30-36 ms), and the track's options without
// --track, are refused before any camera starts.
TEST_F(MeasureTrack, ExposureOutsideTheCalibrationAndStrayOptionsAreRefused) {
  std::string output;
  EXPECT_EQ(Track("outside", {"--exposure-ms", "20", "--count", "1"}, &output), 2) << output;
  EXPECT_NE(output.find("outside the calibrated exposures"), std::string::npos) << output;
  EXPECT_NE(output.find("--exposure-ms inside them"), std::string::npos) << output;
  testing::LoopbackGvcpLock lock;
  EXPECT_EQ(RunIrdist({"measure", "--model", Model(), "--check-every", "1", "--count", "1"},
                      *dir_ + "/stray.log", &output),
            2)
      << output;
  EXPECT_NE(output.find("go with --track"), std::string::npos) << output;
}

}  // namespace
}  // namespace irdist
