// Data safety of a live run (app/runs/run.cc, app/runs/capture.cc): a bracket is committed to the
// recording as soon as it is complete and the station confirmed alive, before anything moves again.
// For a refused move, an emergency stop, a silent station and a kill -9 during the move after a
// bracket: the brackets taken before are in the recording, and `--resume` completes the run with no
// frame twice. An open IRED stops the run with the message. A real full disk (a small tmpfs) stops
// the run with the first error, keeps the brackets before it and leaves a run that resumes.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/mount.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <map>
#include <set>

#include "acquisition/recording_reader.h"
#include "tests/integration/run_helpers.h"
#include "tests/loopback_gvcp.h"

namespace irdist {
namespace {

// Three poses of two frames: the moves are home -> 1500 (MOVE 1), -> 2000 (2), -> 2500 (3).
constexpr const char* kRecipe = R"(name: it-safety
rig: rig.yaml
after: none
axes:
  slide_mm: [1500, 2000, 2500]
  theta_deg: [0]
  bias_ma: [500]
bracket:
  t_ref_ms: 8
  t_meas_ms: [30]
)";
constexpr const char* kTimeScale = "50";

// The virtual rig with `extra` added to its station emulator's options and a short reply timeout.
std::string RigWith(const std::string& extra) {
  std::string rig =
      testing::ReadAll(std::string(IRDIST_SOURCE_DIR) + "/recipes/rigs/virtual.yaml");
  const std::string key = "    reboot_after_s: -1.0";
  const std::size_t at = rig.find(key);
  if (at == std::string::npos) return "";
  rig.insert(rig.find('\n', at) + 1, extra);
  const std::string timeout = "reply_timeout_ms: 500";
  rig.replace(rig.find(timeout), timeout.size(), "reply_timeout_ms: 100");
  return rig;
}

// Rows per (bracket, frame in bracket) of a recording.
std::map<std::pair<std::int64_t, int>, int> Rows(const std::string& recording) {
  std::map<std::pair<std::int64_t, int>, int> seen;
  const RecordingReader reader(recording);
  for (const FrameRecord& row : reader.rows()) ++seen[{row.bracket_id, row.frame_in_bracket}];
  return seen;
}

void ExpectEveryFrameOnce(const std::string& recording) {
  const std::map<std::pair<std::int64_t, int>, int> rows = Rows(recording);
  EXPECT_EQ(rows.size(), 6u);
  for (const auto& [position, count] : rows) {
    EXPECT_EQ(count, 1) << "bracket " << position.first << " frame " << position.second;
  }
  EXPECT_TRUE(RecordingReader(recording).IsComplete());
}

class DataSafety : public ::testing::TestWithParam<std::string> {};

// The third move fails (refused, e-stop, silent station): the two brackets before it are in the
// recording; with the fault gone, --resume records the third one only.
TEST_P(DataSafety, AFaultDuringAMoveKeepsTheBracketsBeforeIt) {
  const std::string fault = GetParam();
  const std::string dir = testing::ScratchDir("data-safety-" + fault);
  const std::string rig = RigWith("    fault_at_move: 3\n    fault: " + fault + "\n");
  ASSERT_FALSE(rig.empty()) << "recipes/rigs/virtual.yaml changed; update this test";
  testing::WriteAll(dir + "/rig.yaml", rig);
  testing::WriteAll(dir + "/recipe.yaml", kRecipe);
  testing::LoopbackGvcpLock lock;
  std::string output;
  const int code = testing::RunIrdist({"calibrate", dir + "/recipe.yaml", "--out", dir + "/run",
                                       "--time-scale", kTimeScale, "--quiet"},
                                      dir + "/run.log", &output);
  EXPECT_EQ(code, 1) << output;
  const std::map<std::pair<std::int64_t, int>, int> kept = Rows(dir + "/run/recording");
  EXPECT_EQ(kept.size(), 4u) << output;  // brackets 0 and 1, two frames each
  EXPECT_EQ(kept.count({0, 0}) + kept.count({0, 1}) + kept.count({1, 0}) + kept.count({1, 1}),
            4u);
  if (fault == "estop") EXPECT_NE(output.find("emergency stop"), std::string::npos) << output;
  if (fault == "refuse") EXPECT_NE(output.find("-222"), std::string::npos) << output;
  // The failed run put the camera back as it found it (camera.restore_after's default).
  EXPECT_NE(output.find("The camera was put back as it was found."), std::string::npos) << output;

  // The same rig file (a resume refuses another one): a new emulator counts its moves from zero,
  // and the one pose left is reached before the third move.
  ASSERT_EQ(testing::RunIrdist({"calibrate", dir + "/recipe.yaml", "--resume", dir + "/run",
                                "--time-scale", kTimeScale, "--quiet"},
                               dir + "/resume.log", &output),
            0)
      << output;
  ExpectEveryFrameOnce(dir + "/run/recording");
}

INSTANTIATE_TEST_SUITE_P(Faults, DataSafety, ::testing::Values("refuse", "estop", "silent"));

// kill -9 while the slide travels to the second pose (a slow slide: 500 mm at 5 mm/s): the first
// bracket is already in the recording; --resume completes the run with no frame twice.
TEST(DataSafetyKill, AKillDuringTheMoveAfterABracketKeepsIt) {
  const std::string dir = testing::ScratchDir("data-safety-kill");
  std::string rig = RigWith("");
  const std::string slide = "speed: 200.0, accel: 400.0";
  ASSERT_NE(rig.find(slide), std::string::npos) << "recipes/rigs/virtual.yaml changed";
  rig.replace(rig.find(slide), slide.size(), "speed: 5.0, accel: 400.0");
  testing::WriteAll(dir + "/rig.yaml", rig);
  testing::WriteAll(dir + "/recipe.yaml", kRecipe);
  testing::LoopbackGvcpLock lock;
  {
    testing::Child child({"calibrate", dir + "/recipe.yaml", "--out", dir + "/run",
                          "--time-scale", kTimeScale, "--quiet"},
                         dir + "/run.log");
    const std::string csv = dir + "/run/recording/frames.csv";
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (child.Running() && testing::CountLines(csv) < 1 + 2 &&
           std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    child.Signal(SIGKILL);
    EXPECT_EQ(child.Wait(std::chrono::seconds(30)), 128 + SIGKILL);
  }
  const std::map<std::pair<std::int64_t, int>, int> kept = Rows(dir + "/run/recording");
  EXPECT_EQ(kept.size(), 2u) << testing::ReadAll(dir + "/run.log");
  std::string output;
  ASSERT_EQ(testing::RunIrdist({"calibrate", dir + "/recipe.yaml", "--resume", dir + "/run",
                                "--time-scale", kTimeScale, "--quiet"},
                               dir + "/resume.log", &output, std::chrono::seconds(180)),
            0)
      << output;
  ExpectEveryFrameOnce(dir + "/run/recording");
}

// An open IRED circuit on irdist's own station: the run stops at the first bracket with the
// measured and set currents, and nothing is recorded at the wrong current.
TEST(DataSafetyCurrent, AnOpenIredStopsTheRunWithTheMessage) {
  const std::string dir = testing::ScratchDir("data-safety-open");
  testing::WriteAll(dir + "/rig.yaml", RigWith("    open_circuit: true\n"));
  testing::WriteAll(dir + "/recipe.yaml", kRecipe);
  testing::LoopbackGvcpLock lock;
  std::string output;
  EXPECT_EQ(testing::RunIrdist({"calibrate", dir + "/recipe.yaml", "--out", dir + "/run",
                                "--time-scale", kTimeScale, "--quiet"},
                               dir + "/run.log", &output),
            1);
  EXPECT_NE(output.find("IRED circuit looks open"), std::string::npos) << output;
  EXPECT_NE(output.find("500.00 mA is set"), std::string::npos) << output;
  EXPECT_TRUE(Rows(dir + "/run/recording").empty());
}


// A small tmpfs mounted at `dir` for the test's life (root only: the test is skipped otherwise).
class SmallDisk {
 public:
  SmallDisk(const std::string& dir, const char* size) : dir_(dir) {
    std::filesystem::create_directories(dir);
    const std::string options = std::string("size=") + size;
    mounted_ = ::mount("tmpfs", dir.c_str(), "tmpfs", MS_NOSUID | MS_NODEV, options.c_str()) == 0;
    if (!mounted_) why_ = std::strerror(errno);
  }
  ~SmallDisk() {
    if (mounted_) ::umount2(dir_.c_str(), MNT_DETACH);
  }
  bool mounted() const { return mounted_; }
  const std::string& why() const { return why_; }
  // Grows the disk in place (the files stay).
  bool Grow(const char* size) {
    const std::string options = std::string("size=") + size;
    return ::mount("tmpfs", dir_.c_str(), "tmpfs", MS_REMOUNT | MS_NOSUID | MS_NODEV,
                   options.c_str()) == 0;
  }

 private:
  std::string dir_, why_;
  bool mounted_ = false;
};

// `irdist calibrate` of the test's recipe on the virtual rig (both written into `dir`) into `run`;
// its exit code, and its output in `output`.
int CalibrateInto(const std::string& dir, const std::string& run, std::string* output) {
  testing::WriteAll(dir + "/rig.yaml", RigWith(""));
  testing::WriteAll(dir + "/recipe.yaml", kRecipe);
  return testing::RunIrdist({"calibrate", dir + "/recipe.yaml", "--out", run, "--time-scale",
                             kTimeScale, "--quiet"},
                            dir + "/run.log", output);
}

// The disk fills during the sweep (room for a few of its 46 KB frames): the run stops with the
// write's own error (ENOSPC), the recording is closed as cut with its complete brackets, and the
// resume command is printed; with room again, --resume completes it with every frame once.
TEST(DataSafetyDisk, AFullDiskStopsWithTheFirstErrorAndTheRunResumes) {
  const std::string dir = testing::ScratchDir("data-safety-full");
  SmallDisk disk(dir + "/disk", "200k");
  if (!disk.mounted()) GTEST_SKIP() << "cannot mount a tmpfs (" << disk.why() << "): needs root";
  testing::LoopbackGvcpLock lock;
  std::string output;
  const std::string run = dir + "/disk/run";
  EXPECT_EQ(CalibrateInto(dir, run, &output), 1);
  const std::size_t first = output.find("No space left on device");
  EXPECT_NE(first, std::string::npos) << output;
  EXPECT_EQ(output.find("also: "), std::string::npos) << "the first error, once: " << output;
  EXPECT_NE(output.find("--resume " + run), std::string::npos) << output;
  const RecordingReader cut(run + "/recording");
  EXPECT_EQ(cut.completion(), Completion::kCut) << output;
  const std::map<std::pair<std::int64_t, int>, int> kept = Rows(run + "/recording");
  EXPECT_LT(kept.size(), 6u) << output;
  EXPECT_EQ(kept.size() % 2, 0u) << "only whole brackets are kept";
  for (const FrameRecord& row : cut.rows()) {
    EXPECT_FALSE(cut.LoadImage(row).empty()) << row.file;
  }

  ASSERT_TRUE(disk.Grow("4m"));
  ASSERT_EQ(testing::RunIrdist({"calibrate", dir + "/recipe.yaml", "--resume", run,
                                "--time-scale", kTimeScale, "--quiet"},
                               dir + "/resume.log", &output),
            0)
      << output;
  ExpectEveryFrameOnce(run + "/recording");
}

// Fills the disk holding `dir` with `dir`/filler until a write fails (no space left).
void FillDisk(const std::string& dir) {
  std::ofstream filler(dir + "/filler", std::ios::binary);
  const std::string block(64 * 1024, '\0');
  while (filler.write(block.data(), block.size()) && filler.flush()) {
  }
}

// The issue: results cut by a full disk said "run again", which was then refused. A live run's
// processing cut by a full disk now names the --resume that completes it, and that command does.
TEST(DataSafetyDisk, AProcessingCutByAFullDiskNamesTheResumeThatCompletesIt) {
  const std::string dir = testing::ScratchDir("data-safety-results");
  SmallDisk disk(dir + "/disk", "4m");
  if (!disk.mounted()) GTEST_SKIP() << "cannot mount a tmpfs (" << disk.why() << "): needs root";
  testing::LoopbackGvcpLock lock;
  std::string output;
  const std::string run = dir + "/disk/run";
  ASSERT_EQ(CalibrateInto(dir, run, &output), 0) << output;
  std::filesystem::remove(run + "/features.csv");  // as if the processing had been cut
  FillDisk(dir + "/disk");
  const std::vector<std::string> resume = {"calibrate", dir + "/recipe.yaml", "--resume", run};
  EXPECT_EQ(testing::RunIrdist(resume, dir + "/full.log", &output), 1);
  EXPECT_NE(output.find("No space left on device"),
            std::string::npos) << output;
  EXPECT_FALSE(std::filesystem::exists(run + "/features.csv")) << "never a cut result";
  const std::string advice =
      "complete the results with: irdist calibrate " + dir + "/recipe.yaml --resume " + run;
  ASSERT_NE(output.find(advice), std::string::npos) << output;
  std::filesystem::remove(dir + "/disk/filler");
  EXPECT_EQ(testing::RunIrdist(resume, dir + "/again.log", &output), 0) << output;
  EXPECT_TRUE(std::filesystem::exists(run + "/features.csv"));
}

}  // namespace
}  // namespace irdist
