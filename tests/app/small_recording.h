#pragma once
// A small hand-made recording for the tests of the processing chain (app/processing/) and the
// offline commands (app/runs/fit_command.h, playback_command.h, check_command.h): a Mono12 spot
// whose brightness scales with the exposure; bracket 0 interleaved (ref 8, meas 30, ref 8, meas
// 36 ms; complete), bracket 1 its reference only (cut).

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "acquisition/recording_writer.h"
#include "tests/integration/run_helpers.h"  // ReadAll

namespace irdist::testing {

// A Mono12 frame with a Gaussian spot whose brightness scales with the exposure.
inline cv::Mat Spot(double exposure_ms, double sigma_px = 4.0) {
  cv::Mat image(128, 160, CV_16UC1, cv::Scalar(16));
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x) {
      const double r2 = (x - 80.0) * (x - 80.0) + (y - 64.0) * (y - 64.0);
      image.at<std::uint16_t>(y, x) = static_cast<std::uint16_t>(
          16 + std::lround(60.0 * exposure_ms * std::exp(-r2 / (2 * sigma_px * sigma_px))));
    }
  }
  return image;
}

class SmallRecordingTest : public ::testing::Test {
 protected:
  void SetUp() override {
    namespace fs = std::filesystem;
    dir_ = fs::temp_directory_path() / ("irdist-small-recording-" + std::to_string(getpid()));
    fs::remove_all(dir_);
    RecordingHeader header;
    header.bit_depth = 12;
    header.pixel_format = "Mono12";
    auto writer = RecordingWriter::Open((dir_ / "recording").string(), header);
    // Bracket 0, interleaved: ref 8, meas 30, ref 8, meas 36 (complete).
    const double exposures[] = {8.0, 30.0, 8.0, 36.0};
    for (int k = 0; k < 4; ++k) {
      FrameRecord r;
      r.bracket_id = 0;
      r.frame_in_bracket = k;
      r.bracket_size = 4;
      r.role = k % 2 == 0 ? FrameRole::kReference : FrameRole::kMeasurement;
      r.requested_exposure_us = r.actual_exposure_us = exposures[k] * 1000.0;
      r.slide_mm = 1800.0;
      r.theta_deg = -10.0;
      r.bias_ma_set = 500.0;
      images_.push_back(Spot(exposures[k] / (k == 2 ? 1.1 : 1.0)));  // the second ref differs
      writer->Append(images_.back(), r);
    }
    // Bracket 1: only its reference (cut).
    FrameRecord r;
    r.bracket_id = 1;
    r.bracket_size = 4;
    r.requested_exposure_us = r.actual_exposure_us = 8000.0;
    images_.push_back(Spot(8.0));
    writer->Append(images_.back(), r);
    writer->Close(Completion::kCut);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  std::filesystem::path dir_;
  std::vector<cv::Mat> images_;
};

}  // namespace irdist::testing
