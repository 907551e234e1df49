// The checks of a resume and the run folder's lock, on hand-made recordings (no camera).
#include "app/resume.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "acquisition/recording.h"
#include "app/errors.h"

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
      writer->Append(cv::Mat(8, 8, CV_16UC1, cv::Scalar(7)), r);
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

TEST(ResumeCommandTest, NamesTheCommandRecipeModelAndFolder) {
  EXPECT_EQ(ResumeCommand("validate", "r.yaml", "m.yaml", "runs/v"),
            "irdist validate r.yaml --model m.yaml --resume runs/v");
}

}  // namespace
}  // namespace irdist
