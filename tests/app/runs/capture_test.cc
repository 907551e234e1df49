// What a resume reads from a recording: recipe text, completion and the complete brackets. (The
// camera side of LiveRecorder runs against the virtual rig in tests/integration/.)
#include "app/runs/capture.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

#include "acquisition/recording_writer.h"

namespace irdist {
namespace {

TEST(CaptureTest, RecordingStateListsCompleteBracketsOnly) {
  const std::string dir =
      (std::filesystem::temp_directory_path() / ("irdist-capture-" + std::to_string(getpid())))
          .string();
  std::filesystem::remove_all(dir);
  {
    RecordingHeader header;
    header.recipe_text = "name: x\n";
    header.recipe_path = "x.yaml";
    auto writer = RecordingWriter::Open(dir, header);
    const cv::Mat image(8, 8, CV_16UC1, cv::Scalar(100));
    for (int bracket = 0; bracket < 3; ++bracket) {
      for (int k = 0; k < (bracket == 1 ? 1 : 2); ++k) {
        FrameRecord r;
        r.bracket_id = bracket;
        r.frame_in_bracket = k;
        r.bracket_size = 2;
        r.role = k == 0 ? FrameRole::kReference : FrameRole::kMeasurement;
        r.requested_exposure_us = r.actual_exposure_us = 8000.0 + 22000.0 * k;  // a real bracket's
        writer->Append(image, r);
      }
    }
    writer->Close(Completion::kCut);
  }
  const RecordingState state = ReadRecordingState(dir);
  EXPECT_EQ(state.recipe_text, "name: x\n");
  EXPECT_EQ(state.recipe_path, "x.yaml");
  EXPECT_FALSE(state.complete);
  EXPECT_EQ(state.complete_brackets, (std::set<std::int64_t>{0, 2}));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace irdist
