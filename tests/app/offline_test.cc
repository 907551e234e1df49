// The processing shared by live runs and playback, on a small hand-made recording: frame features
// (from the cache or the PNG, identical), features.csv, and the pairing of measurement frames with
// their reference (interleaved brackets; incomplete brackets left out).
#include "app/offline.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "acquisition/recording.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;

// A Mono12 frame with a Gaussian spot whose brightness scales with the exposure.
cv::Mat Spot(double exposure_ms, double sigma_px = 4.0) {
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

std::string ReadAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

class OfflineTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("irdist-offline-test-" + std::to_string(getpid()));
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
  void TearDown() override { fs::remove_all(dir_); }

  fs::path dir_;
  std::vector<cv::Mat> images_;
};

TEST(OfflineBitDepth, FollowsThePixelFormat) {
  EXPECT_EQ(BitDepthOfPixelFormat("Mono8"), 8);
  EXPECT_EQ(BitDepthOfPixelFormat("Mono10"), 10);
  EXPECT_EQ(BitDepthOfPixelFormat("Mono12"), 12);
  EXPECT_EQ(BitDepthOfPixelFormat("Mono16"), 16);
}

TEST_F(OfflineTest, FeaturesFromPngEqualFeaturesFromMemory) {
  const RecordingReader reader((dir_ / "recording").string());
  const FeatureOptions options;
  const FeatureMap from_png = RecordingFeatures(reader, options);
  ASSERT_EQ(from_png.size(), 5u);
  FeatureMap cache;
  for (size_t i = 0; i < images_.size(); ++i) {
    cache[static_cast<std::int64_t>(i)] = FrameFeatures(images_[i], 12, options);
    EXPECT_EQ(cache[static_cast<std::int64_t>(i)].e_rel,
              from_png.at(static_cast<std::int64_t>(i)).e_rel);
    EXPECT_EQ(cache[static_cast<std::int64_t>(i)].sigma,
              from_png.at(static_cast<std::int64_t>(i)).sigma);
  }
  // A cached entry is taken as is (the live run's in-memory frames).
  cache[2].e_rel = 42.0;
  cache.erase(4);
  const FeatureMap mixed = RecordingFeatures(reader, options, cache);
  EXPECT_EQ(mixed.at(2).e_rel, 42.0);
  EXPECT_EQ(mixed.at(4).e_rel, from_png.at(4).e_rel);

  const std::string a = (dir_ / "a.csv").string(), b = (dir_ / "b.csv").string();
  WriteFeaturesCsv(a, reader.rows(), from_png);
  WriteFeaturesCsv(b, reader.rows(), RecordingFeatures(reader, options, FeatureMap{{0, cache[0]}}));
  EXPECT_EQ(ReadAll(a), ReadAll(b));
  std::istringstream lines(ReadAll(a));
  std::string header, first;
  std::getline(lines, header);
  std::getline(lines, first);
  EXPECT_EQ(header.rfind("index,file,bracket,frame_in_bracket,role,exposure_us", 0), 0u);
  EXPECT_EQ(first.rfind("0,frames/000000.png,0,0,ref,8000,", 0), 0u) << first;
  int rows = 0;
  for (std::string line; std::getline(lines, line);) ++rows;
  EXPECT_EQ(rows, 4);  // plus the first: 5 frames
}

TEST_F(OfflineTest, MeasurementsPairWithThePrecedingReferenceOfCompleteBrackets) {
  const RecordingReader reader((dir_ / "recording").string());
  const FeatureMap features = RecordingFeatures(reader, FeatureOptions{});
  const std::vector<CalibrationSample> samples = SamplesFromRecording(reader, features);
  ASSERT_EQ(samples.size(), 2u);  // bracket 1 is incomplete
  EXPECT_EQ(samples[0].t_ref_ms, 8.0);
  EXPECT_EQ(samples[0].t_ms, 30.0);
  EXPECT_EQ(samples[1].t_ms, 36.0);
  EXPECT_EQ(samples[0].reference.e_rel, features.at(0).e_rel);
  EXPECT_EQ(samples[1].reference.e_rel, features.at(2).e_rel);  // the retaken reference
  EXPECT_NE(features.at(0).e_rel, features.at(2).e_rel);
  EXPECT_EQ(samples[0].d_mm, 1800.0);
  EXPECT_EQ(samples[0].theta_deg, 10.0);  // |theta|: the sign is not observable
  EXPECT_EQ(samples[0].bias_ma, 500.0);
}

TEST_F(OfflineTest, FitRefusesARecordingTooSmallForTheModels) {
  const RecordingReader reader((dir_ / "recording").string());
  const FeatureMap features = RecordingFeatures(reader, FeatureOptions{});
  std::ostringstream out;
  EXPECT_THROW(
      FitRecording(reader, features, FeatureOptions{}, (dir_ / "model.yaml").string(), "", out),
      RecordingError);
  EXPECT_FALSE(fs::exists(dir_ / "model.yaml"));
}

}  // namespace
}  // namespace irdist
