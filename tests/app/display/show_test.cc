// playback --show without a display: a clear error, no window and no crash.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>

#include "acquisition/recording_reader.h"
#include "acquisition/recording_writer.h"
#include "app/display/show.h"

namespace irdist {
namespace {

TEST(ShowTest, WithoutADisplaySaysSo) {
  const std::string dir =
      (std::filesystem::temp_directory_path() / ("irdist-show-" + std::to_string(getpid())))
          .string();
  std::filesystem::remove_all(dir);
  {
    RecordingHeader header;
    auto writer = RecordingWriter::Open(dir, header);
    FrameRecord record;
    record.bracket_size = 1;
    record.requested_exposure_us = record.actual_exposure_us = 8000.0;  // a real frame's
    writer->Append(cv::Mat(8, 8, CV_16UC1, cv::Scalar(100)), record);
    writer->Close(Completion::kComplete);
  }
  unsetenv("DISPLAY");
  unsetenv("WAYLAND_DISPLAY");
  const RecordingReader reader(dir);
  try {
    ShowPlayback(reader, {}, {});
    ADD_FAILURE() << "no error";
  } catch (const DisplayError& e) {
    EXPECT_NE(std::string(e.what()).find("display"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace irdist
