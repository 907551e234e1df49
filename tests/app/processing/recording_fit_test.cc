// Calibration from a recording: the pairing of measurement frames with their reference
// (interleaved brackets; incomplete brackets left out), a recording too small for the models, and
// the camera response recovered from the brackets.
#include "app/processing/recording_fit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>

#include "acquisition/recording_reader.h"
#include "acquisition/recording_writer.h"
#include "app/processing/frame_features.h"
#include "tests/app/small_recording.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;
using testing::SmallRecordingTest;
using testing::Spot;

TEST_F(SmallRecordingTest, MeasurementsPairWithThePrecedingReferenceOfCompleteBrackets) {
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

// Off the pan and tilt axes' line (virtual-offset: the IRED 40 mm right of and 30 mm above the
// optical axis) a sample's known range and theta are the pose's true ones, from the camera and from
// the line of sight, as its features turned onto the line of sight show them (not the slide and
// the pan: the fit's fitness found the difference, 0.77% in the minor axis at 1.5 m).
TEST(SamplesFromRecording, OffTheAxisTheyTakeTheTrueRangeAndTheta) {
  const fs::path dir =
      fs::temp_directory_path() / ("irdist-offset-samples-" + std::to_string(getpid()));
  fs::remove_all(dir);
  RecordingHeader header;
  header.bit_depth = 12;
  header.pixel_format = "Mono12";
  std::ifstream rig(std::string(IRDIST_SOURCE_DIR) + "/recipes/rigs/virtual-offset.yaml");
  header.rig_text.assign(std::istreambuf_iterator<char>(rig), {});
  ASSERT_NE(header.rig_text.find("offset_x_mm: 40"), std::string::npos);
  {
    auto writer = RecordingWriter::Open((dir / "recording").string(), header);
    for (int k = 0; k < 2; ++k) {
      FrameRecord r;
      r.bracket_size = 2;
      r.frame_in_bracket = k;
      r.role = k == 0 ? FrameRole::kReference : FrameRole::kMeasurement;
      r.requested_exposure_us = r.actual_exposure_us = (k == 0 ? 8.0 : 30.0) * 1000.0;
      r.slide_mm = 1500.0;
      r.pan_deg = 20.0;
      r.theta_deg = 20.0;
      r.bias_ma_set = 500.0;
      writer->Append(Spot(k == 0 ? 8.0 : 30.0), r);
    }
    writer->Close(Completion::kComplete);
  }
  const RecordingReader reader((dir / "recording").string());
  const std::vector<CalibrationSample> samples =
      SamplesFromRecording(reader, RecordingFeatures(reader, FeatureOptions{}));
  fs::remove_all(dir);
  ASSERT_EQ(samples.size(), 1u);
  // The centre (40, -30, 1500) mm; the IRED's axis (sin 20, 0, -cos 20); theta from -centre.
  const double range_mm = std::sqrt(40.0 * 40.0 + 30.0 * 30.0 + 1500.0 * 1500.0);
  const double pan = 20.0 * M_PI / 180.0;
  const double cos_theta = (1500.0 * std::cos(pan) - 40.0 * std::sin(pan)) / range_mm;
  EXPECT_NEAR(samples[0].d_mm, range_mm, 1e-9);
  EXPECT_NEAR(samples[0].theta_deg, std::acos(cos_theta) * 180.0 / M_PI, 1e-9);
  EXPECT_GT(std::fabs(samples[0].theta_deg - 20.0), 1.5);  // 21.56 deg: 1.56 deg from the pan
  EXPECT_EQ(samples[0].pose, 0);
}

TEST_F(SmallRecordingTest, FitRefusesARecordingTooSmallForTheModels) {
  const RecordingReader reader((dir_ / "recording").string());
  const FeatureMap features = RecordingFeatures(reader, FeatureOptions{});
  std::ostringstream out;
  EXPECT_THROW(
      FitRecording(reader, features, FeatureOptions{}, (dir_ / "model.yaml").string(), {}, out),
      RecordingError);
  EXPECT_FALSE(fs::exists(dir_ / "model.yaml"));
}

// A 12-bit frame as a compressive camera gives it: y = x - a x^2 / 4095 on each value, rounded
// (sim/sensor.cc's form).
cv::Mat Compress(const cv::Mat& linear, double a) {
  cv::Mat out(linear.size(), CV_16UC1);
  for (int y = 0; y < linear.rows; ++y) {
    for (int x = 0; x < linear.cols; ++x) {
      const double v = linear.at<std::uint16_t>(y, x);
      out.at<std::uint16_t>(y, x) = static_cast<std::uint16_t>(std::lround(v - a * v * v / 4095.0));
    }
  }
  return out;
}

// A complete recording at `path` of four brackets at 1800 mm and 500 mA, spots of sigma 3, 4, 5
// and 6 px, each an 8 ms reference and measurements at 30, 32, 34 and 36 ms, every frame
// compressed by Compress(frame, a).
void WriteCompressedBrackets(const std::string& path, const RecordingHeader& header, double a) {
  auto writer = RecordingWriter::Open(path, header);
  int bracket = 0;
  for (double sigma_px : {3.0, 4.0, 5.0, 6.0}) {
    const double exposures[] = {8.0, 30.0, 32.0, 34.0, 36.0};
    for (int k = 0; k < 5; ++k) {
      FrameRecord r;
      r.bracket_id = bracket;
      r.frame_in_bracket = k;
      r.bracket_size = 5;
      r.role = k == 0 ? FrameRole::kReference : FrameRole::kMeasurement;
      r.requested_exposure_us = r.actual_exposure_us = exposures[k] * 1000.0;
      r.slide_mm = 1800.0;
      r.bias_ma_set = 500.0;
      writer->Append(Compress(Spot(exposures[k], sigma_px), a), r);
    }
    ++bracket;
  }
  writer->Close(Completion::kComplete);
}

// A recording whose recipe asks for the camera response, made with a compressive camera
// (y = x - a x^2 / 4095 on the 12-bit value, sim/sensor.cc's form): the recovery reads the
// brackets and returns the camera's inverse, and the features then use it on every pixel.
TEST(OfflineResponse, RecoversTheCurveFromTheRecordingsBrackets) {
  const fs::path dir =
      fs::temp_directory_path() / ("irdist-offline-response-" + std::to_string(getpid()));
  fs::remove_all(dir);
  const double a = 0.1;
  RecordingHeader header;
  header.bit_depth = 12;
  header.pixel_format = "Mono12";
  header.recipe_path = "recover.yaml";
  header.recipe_text = "after: fit\ncalibration:\n  camera_response: recover\n";
  WriteCompressedBrackets((dir / "recording").string(), header, a);
  const RecordingReader reader((dir / "recording").string());
  EXPECT_TRUE(RecipeAsksForResponse(reader));
  std::ostringstream out;
  const ResponseRecovery recovery = RecoverRecordingResponse(reader, FeatureOptions{}, out);
  EXPECT_NE(out.str().find("camera response: 17 knots"), std::string::npos) << out.str();
  EXPECT_EQ(recovery.stacks_used, 4);
  // The camera's inverse from its formula: x(M) - 16 (black level), up to f's scale.
  auto truth = [a](double m) {
    return 4095.0 * (1.0 - std::sqrt(1.0 - 4.0 * a * m)) / (2.0 * a) - 16.0;
  };
  const double mid = 0.3;
  for (double m = recovery.gray_min + 0.02; m < recovery.gray_max - 0.02; m += 0.02) {
    EXPECT_NEAR(recovery.curve.Apply(m) / recovery.curve.Apply(mid), truth(m) / truth(mid), 0.005)
        << "M = " << m << "; " << recovery.BriefReport();
  }
  const FeatureOptions with = WithResponse(FeatureOptions{}, recovery);
  EXPECT_EQ(with.response_scope, ResponseScope::kAllPixels);
  EXPECT_EQ(with.inverse_response.f, recovery.curve.f);
  // A recording without the recipe key does not ask for it.
  RecordingHeader plain = header;
  plain.recipe_text = "after: fit\n";
  {
    auto writer = RecordingWriter::Open((dir / "plain").string(), plain);
    writer->Close(Completion::kComplete);
  }
  EXPECT_FALSE(RecipeAsksForResponse(RecordingReader((dir / "plain").string())));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace irdist
