// Ctrl-C (SIGINT) and a crash (SIGKILL) in the middle of a run, then `--resume`: the recording ends
// with the same frame set as an uninterrupted run of the same recipe (same pose/exposure rows, none
// twice, none missing), and the checker finds nothing wrong.
#include <gtest/gtest.h>
#include <signal.h>

#include <filesystem>
#include <map>
#include <set>
#include <tuple>

#include "acquisition/recording_check.h"
#include "acquisition/recording_reader.h"
#include "tests/integration/run_helpers.h"
#include "tests/loopback_gvcp.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;
using testing::RunIrdist;

// 16 poses x 3 frames = 48 rows; record only (after: none).
constexpr const char* kRecipe = R"(name: it-resume
rig: virtual
after: none
axes:
  slide_mm: [1500, 2500]
  theta_deg: [0, 20]
  bias_ma: [475, 500]
bracket:
  t_ref_ms: 8
  t_meas_ms: [30, 36]
  repeats: 2
)";
constexpr int kRows = 48;
constexpr const char* kTimeScale = "50";

// What identifies a frame of the sweep, independent of when it was taken.
using FrameKey = std::tuple<std::int64_t, int, std::string, double, double, double, double, int>;

std::set<FrameKey> FrameSet(const std::string& recording, int* brackets, int* incomplete) {
  const RecordingReader reader(recording);
  std::set<FrameKey> keys;
  *brackets = 0;
  *incomplete = 0;
  for (const RecordedBracket& b : reader.Brackets()) {
    ++*brackets;
    if (!b.complete) ++*incomplete;
    for (const FrameRecord& f : b.frames) {
      keys.insert({f.bracket_id, f.frame_in_bracket, FrameRoleName(f.role), f.requested_exposure_us,
                   f.slide_mm, f.theta_deg, f.bias_ma_set, f.repeat});
    }
  }
  return keys;
}

class Resume : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new std::string(testing::ScratchDir("resume"));
    testing::WriteAll(*dir_ + "/recipe.yaml", kRecipe);
    testing::LoopbackGvcpLock lock;
    std::string output;
    reference_code_ = RunIrdist({"calibrate", *dir_ + "/recipe.yaml", "--out", *dir_ + "/whole",
                                 "--time-scale", kTimeScale, "--quiet"},
                                *dir_ + "/whole.log", &output);
    if (reference_code_ == 0) {
      reference_ = new std::set<FrameKey>(
          FrameSet(*dir_ + "/whole/recording", &reference_brackets_, &reference_incomplete_));
    }
  }
  static void TearDownTestSuite() {
    delete dir_;
    delete reference_;
  }

  // Starts a run, sends `signal` once frames.csv holds `rows` frame rows, returns the exit code.
  static int Interrupt(const std::string& name, int signal, int rows) {
    testing::Child child({"calibrate", *dir_ + "/recipe.yaml", "--out", *dir_ + "/" + name,
                          "--time-scale", kTimeScale, "--quiet"},
                         *dir_ + "/" + name + "-cut.log");
    const std::string csv = *dir_ + "/" + name + "/recording/frames.csv";
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (child.Running() && testing::CountLines(csv) < 1 + rows &&
           std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    child.Signal(signal);
    return child.Wait(std::chrono::seconds(60));
  }

  static std::string* dir_;
  static int reference_code_;
  static std::set<FrameKey>* reference_;
  static int reference_brackets_;
  static int reference_incomplete_;
};

std::string* Resume::dir_ = nullptr;
int Resume::reference_code_ = -1;
std::set<FrameKey>* Resume::reference_ = nullptr;
int Resume::reference_brackets_ = 0;
int Resume::reference_incomplete_ = 0;

TEST_F(Resume, AnUninterruptedRunRecordsEveryFrameOnce) {
  ASSERT_EQ(reference_code_, 0) << testing::ReadAll(*dir_ + "/whole.log");
  EXPECT_EQ(reference_->size(), static_cast<size_t>(kRows));
  EXPECT_EQ(reference_brackets_, 16);
  EXPECT_EQ(reference_incomplete_, 0);
  EXPECT_EQ(testing::CountLines(*dir_ + "/whole/features.csv"), 1 + kRows);
}

TEST_F(Resume, CtrlCClosesTheRecordingAsCutAndResumeCompletesIt) {
  ASSERT_EQ(reference_code_, 0);
  testing::LoopbackGvcpLock lock;
  const int code = Interrupt("sigint", SIGINT, 9);
  const std::string log = testing::ReadAll(*dir_ + "/sigint-cut.log");
  ASSERT_EQ(code, 130) << log;
  EXPECT_NE(log.find("--resume " + *dir_ + "/sigint"), std::string::npos) << log;
  const std::string recording = *dir_ + "/sigint/recording";
  {
    const RecordingReader cut(recording);
    EXPECT_EQ(cut.completion(), Completion::kCut);
    const size_t cut_rows = cut.rows().size();
    EXPECT_GE(cut_rows, 9u);
    EXPECT_LT(cut_rows, static_cast<size_t>(kRows)) << "the run was not cut";
    EXPECT_EQ(cut_rows % 3, 0u) << "the bracket in flight was not finished";
  }
  std::string output;
  ASSERT_EQ(RunIrdist({"calibrate", *dir_ + "/recipe.yaml", "--resume", *dir_ + "/sigint",
                       "--time-scale", kTimeScale, "--quiet"},
                      *dir_ + "/sigint-resume.log", &output),
            0)
      << output;
  int brackets = 0, incomplete = 0;
  EXPECT_EQ(FrameSet(recording, &brackets, &incomplete), *reference_);
  EXPECT_EQ(incomplete, 0);
  const RecordingReader done(recording);
  EXPECT_TRUE(done.IsComplete());
  EXPECT_EQ(done.rows().size(), static_cast<size_t>(kRows)) << "a frame was taken twice";
  EXPECT_EQ(done.header().resumed.size(), 1u);
  const RecordingCheck check = CheckRecording(recording);
  EXPECT_TRUE(check.ok()) << check.BriefReport();
  EXPECT_TRUE(fs::exists(*dir_ + "/sigint/station.1.log"));
  EXPECT_TRUE(fs::exists(*dir_ + "/sigint/station.log"));
}

TEST_F(Resume, AKilledRunIsResumedWithoutGapOrDuplicate) {
  ASSERT_EQ(reference_code_, 0);
  testing::LoopbackGvcpLock lock;
  const int code = Interrupt("sigkill", SIGKILL, 12);
  ASSERT_EQ(code, 128 + SIGKILL) << testing::ReadAll(*dir_ + "/sigkill-cut.log");
  const std::string recording = *dir_ + "/sigkill/recording";
  EXPECT_EQ(RecordingReader(recording).completion(), Completion::kRunning);
  std::string output;
  ASSERT_EQ(RunIrdist({"calibrate", *dir_ + "/recipe.yaml", "--resume", *dir_ + "/sigkill",
                       "--time-scale", kTimeScale, "--quiet"},
                      *dir_ + "/sigkill-resume.log", &output),
            0)
      << output;
  int brackets = 0, incomplete = 0;
  EXPECT_EQ(FrameSet(recording, &brackets, &incomplete), *reference_);
  EXPECT_EQ(incomplete, 0);
  EXPECT_EQ(brackets, reference_brackets_);
  const RecordingCheck check = CheckRecording(recording);
  EXPECT_TRUE(check.ok()) << check.BriefReport();
  // Every (bracket, position) appears once, except the positions of a bracket that the kill cut
  // while it was being written: those were retaken as a whole.
  const RecordingReader done(recording);
  std::map<std::pair<std::int64_t, int>, int> seen;
  for (const FrameRecord& row : done.rows()) ++seen[{row.bracket_id, row.frame_in_bracket}];
  int retaken = 0;
  for (const auto& [key, count] : seen) {
    EXPECT_LE(count, 2);
    retaken += count - 1;
  }
  EXPECT_LT(retaken, 3) << "more than one partial bracket was retaken";
}

TEST_F(Resume, ResumeRefusesAnotherRecipe) {
  ASSERT_EQ(reference_code_, 0);
  std::string changed = kRecipe;
  changed.replace(changed.find("[475, 500]"), 10, "[475, 510]");
  testing::WriteAll(*dir_ + "/other.yaml", changed);
  // The recording is complete and the recipe differs: nothing starts.
  std::string output;
  EXPECT_EQ(RunIrdist({"calibrate", *dir_ + "/other.yaml", "--resume", *dir_ + "/whole"},
                      *dir_ + "/other.log", &output),
            1)
      << output;
  EXPECT_NE(output.find("differs from the recipe recorded"), std::string::npos) << output;
}

TEST_F(Resume, ResumeOfACompleteRunSaysSoAndRefitsNothing) {
  ASSERT_EQ(reference_code_, 0);
  const std::string model = *dir_ + "/whole/features.csv";  // the recipe's after: none
  ASSERT_TRUE(fs::exists(model));
  const auto written = fs::last_write_time(model);
  std::string output;
  EXPECT_EQ(RunIrdist({"calibrate", *dir_ + "/recipe.yaml", "--resume", *dir_ + "/whole"},
                      *dir_ + "/again.log", &output),
            1)
      << output;
  EXPECT_NE(output.find("nothing to resume"), std::string::npos) << output;
  EXPECT_EQ(fs::last_write_time(model), written) << "the complete run was processed again";
}

// The issue: killed (kill -9) during the processing after the recording, the folder has a complete
// recording and no result; `--resume` said the results stand. Now it runs the processing (here
// the features of `after: none`; model.yaml and the report for a fit) without starting the rig.
TEST_F(Resume, AResumeFinishesAProcessingThatWasKilled) {
  ASSERT_EQ(reference_code_, 0);
  const std::string run = *dir_ + "/killed-in-processing";
  fs::remove_all(run);
  fs::copy(*dir_ + "/whole", run, fs::copy_options::recursive);
  fs::remove(run + "/features.csv");
  std::string output;
  EXPECT_EQ(RunIrdist({"calibrate", *dir_ + "/recipe.yaml", "--resume", run},
                      *dir_ + "/killed-in-processing.log", &output),
            0)
      << output;
  EXPECT_NE(output.find("features.csv is missing"), std::string::npos) << output;
  EXPECT_EQ(testing::CountLines(run + "/features.csv"), 1 + kRows);
  EXPECT_EQ(testing::ReadAll(run + "/features.csv"), testing::ReadAll(*dir_ + "/whole/features.csv"));
}

}  // namespace
}  // namespace irdist
