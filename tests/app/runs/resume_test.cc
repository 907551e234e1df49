// The checks of a resume and the run folder's lock, on hand-made recordings (no camera).
#include "app/runs/resume.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "acquisition/recording_writer.h"
#include "app/inputs/errors.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;

const char kCrlfRecipe[] = "name: crlf\r\naxes:\r\n  slide_mm: 2000\r\n";  // and no final newline

class ResumeTest : public ::testing::Test {
 protected:
  void SetUp() override {
    run_ = (fs::temp_directory_path() / ("irdist-resume-test-" + std::to_string(getpid()))).string();
    fs::remove_all(run_);
  }
  void TearDown() override { fs::remove_all(run_); }

  // A cut recording of `command` with one complete bracket and the given recipe text.
  void MakeCutRun(const std::string& command, Completion completion = Completion::kCut) {
    { const RunFolderLock lock(run_, command); }
    RecordingHeader header;
    header.pixel_format = "Mono12";
    header.bit_depth = 12;
    header.run_command = command;
    header.camera_features = {{"OffsetX", "512"}, {"OffsetY", "384"}, {"Width", "256"},
                              {"Height", "256"}};
    header.recipe_text = kCrlfRecipe;
    header.rig_text = "kind: virtual\n";
    auto writer = RecordingWriter::Open(run_ + "/recording", header);
    for (int k = 0; k < 2; ++k) {
      FrameRecord r;
      r.frame_in_bracket = k;
      r.bracket_size = 2;
      r.role = k == 0 ? FrameRole::kReference : FrameRole::kMeasurement;
      r.requested_exposure_us = r.actual_exposure_us = 8000.0 + 22000.0 * k;  // a real bracket's
      writer->Append(cv::Mat(8, 8, CV_16UC1, cv::Scalar(7 + k)), r);
    }
    writer->Close(completion);
  }

  ResumeExpectation Same() const {
    ResumeExpectation e;
    e.recipe_path = "r.yaml";
    e.recipe_text = kCrlfRecipe;
    e.rig_path = "rig.yaml";
    e.rig_text = "kind: virtual\n";
    e.pixel_format = "Mono12";
    e.roi_offset_x = 512;
    e.roi_offset_y = 384;
    e.roi_width = 256;
    e.roi_height = 256;
    return e;
  }

  std::string run_;
};

TEST_F(ResumeTest, CrlfRecipeWithoutFinalNewlineResumes) {
  MakeCutRun("calibrate");
  const ResumeState state = CheckResume(run_, "calibrate", Same());
  EXPECT_EQ(state.complete_brackets, (std::set<std::int64_t>{0}));
}

TEST_F(ResumeTest, SecondRunOnTheFolderIsRefusedNamingThePid) {
  const RunFolderLock first(run_, "calibrate");
  try {
    const RunFolderLock second(run_, "calibrate");
    FAIL() << "two runs on one folder";
  } catch (const RunFolderError& e) {
    EXPECT_NE(std::string(e.what()).find("process " + std::to_string(getpid())), std::string::npos)
        << e.what();
  }
}

TEST_F(ResumeTest, FolderOfAnotherCommandIsRefused) {
  MakeCutRun("calibrate");
  try {
    CheckResume(run_, "validate", Same());
    FAIL() << "validate --resume accepted a calibrate folder";
  } catch (const RunFolderError& e) {
    EXPECT_NE(std::string(e.what()).find("`irdist calibrate` run"), std::string::npos) << e.what();
  }
}

TEST_F(ResumeTest, CompleteRunIsNotResumed) {
  MakeCutRun("calibrate", Completion::kComplete);
  try {
    CheckResume(run_, "calibrate", Same());
    FAIL() << "a complete run was resumed";
  } catch (const RunFolderError& e) {
    EXPECT_NE(std::string(e.what()).find("nothing to resume"), std::string::npos) << e.what();
  }
}

TEST_F(ResumeTest, ChangedRigOrCameraSettingsAreRefused) {
  MakeCutRun("calibrate");
  ResumeExpectation mono8 = Same();
  mono8.pixel_format = "Mono8";
  mono8.roi_width = 128;
  try {
    CheckResume(run_, "calibrate", mono8);
    FAIL() << "a resume with Mono8 and another ROI was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.File(), "rig.yaml");
    EXPECT_NE(std::string(e.what()).find("pixel format Mono8 (recorded: Mono12)"),
              std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("Width 128 (recorded: 256)"), std::string::npos)
        << e.what();
  }
  ResumeExpectation edited = Same();
  edited.rig_text = "kind: virtual\n# edited\n";
  EXPECT_THROW(CheckResume(run_, "calibrate", edited), InputError);
  ResumeExpectation lf = Same();
  lf.recipe_text = "name: crlf\naxes:\n  slide_mm: 2000\n";
  EXPECT_THROW(CheckResume(run_, "calibrate", lf), InputError);
}

// The issue: `--resume` appended to a recording with a replaced frame (found only after the
// whole resumed sweep) or edited rows, and hashed them as its own. Check's errors come first.
TEST_F(ResumeTest, ARecordingWithErrorsIsNotResumedAndItsErrorsAreListed) {
  MakeCutRun("calibrate");
  const fs::path frame = fs::path(run_) / "recording/frames/000001.png";
  fs::copy_file(fs::path(run_) / "recording/frames/000000.png", frame,
                fs::copy_options::overwrite_existing);
  try {
    CheckResume(run_, "calibrate", Same());
    FAIL() << "a recording with a replaced frame was resumed";
  } catch (const CheckFailedError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("it is not resumed"), std::string::npos) << what;
    EXPECT_NE(what.find("frames/000001.png: its content is not the frame recorded in its row"),
              std::string::npos) << what;
  }
}

// The issue: once run.lock was deleted, validate --resume took over a calibrate folder.
TEST_F(ResumeTest, FolderOfAnotherCommandIsRefusedWithoutItsRunLock) {
  MakeCutRun("calibrate");
  fs::remove(fs::path(run_) / "run.lock");
  try {
    CheckResume(run_, "validate", Same());
    FAIL() << "validate --resume accepted a calibrate folder without its run.lock";
  } catch (const RunFolderError& e) {
    EXPECT_NE(std::string(e.what()).find("`irdist calibrate` run"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(CheckResume(run_, "calibrate", Same()));
}

// The issue: `calibrate --out FILE` said "filesystem error".
TEST_F(ResumeTest, ARunFolderThatIsAFileIsRefusedNamingIt) {
  std::ofstream(run_) << "not a folder\n";
  try {
    CreateRunFolder(run_);
    FAIL() << "a file was taken as a run folder";
  } catch (const RunFolderError& e) {
    EXPECT_NE(std::string(e.what()).find(run_ + " exists and is not a folder (a file)"),
              std::string::npos) << e.what();
  }
  EXPECT_THROW(RunFolderLock(run_, "calibrate"), RunFolderError);
  fs::remove(run_);
  CreateRunFolder(run_ + "/a/b");
  EXPECT_TRUE(fs::is_directory(run_ + "/a/b"));
}

TEST(ResumeCommandTest, NamesTheCommandRecipeModelAndFolder) {
  EXPECT_EQ(ResumeCommand("validate", "r.yaml", "m.yaml", "runs/v"),
            "irdist validate r.yaml --model m.yaml --resume runs/v");
}

// The printed command pastes into a shell as it is: spaces, '#', '$' and quotes are quoted.
TEST(ResumeCommandTest, QuotesEveryWordAShellWouldSplitOrExpand) {
  EXPECT_EQ(ResumeCommand("calibrate", "lab #2/r.yaml", "", "runs/it's $HOME"),
            "irdist calibrate 'lab #2/r.yaml' --resume 'runs/it'\\''s $HOME'");
  EXPECT_EQ(ShellQuoted("runs/a-b_c.d:e=f,g+h@i%j"), "runs/a-b_c.d:e=f,g+h@i%j");
  EXPECT_EQ(ShellQuoted(""), "''");
  EXPECT_EQ(ShellQuoted("a;b"), "'a;b'");
}

// Killed during the fit step: the recording is complete, model.yaml is missing. The resume now
// goes on to the processing instead of saying the results stand.
TEST_F(ResumeTest, CompleteRunWithoutItsModelIsProcessedByTheResume) {
  MakeCutRun("calibrate", Completion::kComplete);
  ResumeExpectation expected = Same();
  expected.results = {"model.yaml", "report/index.html"};
  ResumeState state = CheckResume(run_, "calibrate", expected);
  EXPECT_TRUE(state.complete);
  EXPECT_EQ(state.missing_result, "model.yaml");
  std::ofstream(run_ + "/model.yaml") << "model\n";
  state = CheckResume(run_, "calibrate", expected);
  EXPECT_EQ(state.missing_result, "report/index.html");  // killed while writing the report
  fs::create_directories(run_ + "/report");
  std::ofstream(run_ + "/report/index.html") << "<html>\n";
  try {
    CheckResume(run_, "calibrate", expected);
    FAIL() << "a finished run was resumed";
  } catch (const RunFolderError& e) {
    EXPECT_NE(std::string(e.what()).find("they stand"), std::string::npos) << e.what();
  }
}

// A model.yaml (or frames/, recording.yaml) that is a link: the resume would write through it.
TEST_F(ResumeTest, ALinkInTheRunFolderIsRefusedNamingIt) {
  MakeCutRun("calibrate");
  const std::string outside = run_ + "-outside.yaml";
  std::ofstream(outside) << "theirs\n";
  fs::create_symlink(outside, run_ + "/model.yaml");
  try {
    CheckResume(run_, "calibrate", Same());
    FAIL() << "a linked model.yaml was accepted";
  } catch (const RunFolderError& e) {
    EXPECT_NE(std::string(e.what()).find(run_ + "/model.yaml is a symbolic link"),
              std::string::npos) << e.what();
  }
  fs::remove(outside);
}

// fit and the like check a folder's lock without taking it (the folder's command stays).
TEST_F(ResumeTest, RefuseLiveRunNamesTheLiveRunAndLeavesTheLockAlone) {
  RefuseLiveRun(run_, "fit");  // no run.lock: free
  {
    const RunFolderLock live(run_, "calibrate");
    try {
      RefuseLiveRun(run_, "fit");
      FAIL() << "fit beside a live run";
    } catch (const RunFolderError& e) {
      EXPECT_NE(std::string(e.what()).find("irdist calibrate, process " +
                                           std::to_string(getpid())),
                std::string::npos) << e.what();
    }
  }
  RefuseLiveRun(run_, "fit");  // the run ended
  MakeCutRun("calibrate");
  EXPECT_NO_THROW(CheckResume(run_, "calibrate", Same()));  // still a calibrate folder
}

}  // namespace
}  // namespace irdist
