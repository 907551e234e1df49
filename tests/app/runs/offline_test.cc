// The processing shared by live runs and playback, on a small hand-made recording: frame features
// (from the cache or the PNG, identical), features.csv, and the pairing of measurement frames with
// their reference (interleaved brackets; incomplete brackets left out).
#include "app/runs/offline.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "acquisition/recording.h"
#include "app/cli/errors.h"
#include "app/runs/resume.h"
#include "app/runs/run.h"

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

// A recording whose recipe asks for the camera response, made with a compressive camera
// (y = x - a x^2 / 4095 on the 12-bit value, sim/sensor.cc's form): the recovery reads the
// brackets and returns the camera's inverse, and the features then use it on every pixel.
TEST(OfflineResponse, RecoversTheCurveFromTheRecordingsBrackets) {
  const fs::path dir =
      fs::temp_directory_path() / ("irdist-offline-response-" + std::to_string(getpid()));
  fs::remove_all(dir);
  const double a = 0.1;
  auto compress = [a](const cv::Mat& linear) {
    cv::Mat out(linear.size(), CV_16UC1);
    for (int y = 0; y < linear.rows; ++y) {
      for (int x = 0; x < linear.cols; ++x) {
        const double v = linear.at<std::uint16_t>(y, x);
        out.at<std::uint16_t>(y, x) =
            static_cast<std::uint16_t>(std::lround(v - a * v * v / 4095.0));
      }
    }
    return out;
  };
  RecordingHeader header;
  header.bit_depth = 12;
  header.pixel_format = "Mono12";
  header.recipe_path = "recover.yaml";
  header.recipe_text = "after: fit\ncalibration:\n  camera_response: recover\n";
  {
    auto writer = RecordingWriter::Open((dir / "recording").string(), header);
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
        writer->Append(compress(Spot(exposures[k], sigma_px)), r);
      }
      ++bracket;
    }
    writer->Close(Completion::kComplete);
  }
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


TEST_F(OfflineTest, PlaybackNeverReplacesResultsWithoutForce) {
  const std::string recording = (dir_ / "recording").string();
  std::ostringstream out, err;
  PlaybackArgs args;
  args.recording = recording;
  RunPlayback(args, {out, err});  // the first playback writes features.csv beside the recording
  const std::string first = ReadAll((dir_ / "features.csv").string());
  std::ofstream(dir_ / "features.csv", std::ios::app) << "# the live run's\n";
  EXPECT_THROW(RunPlayback(args, {out, err}), RunFolderError);
  EXPECT_EQ(ReadAll((dir_ / "features.csv").string()), first + "# the live run's\n");
  args.force = true;
  RunPlayback(args, {out, err});
  EXPECT_EQ(ReadAll((dir_ / "features.csv").string()), first);
}

TEST_F(OfflineTest, FitAndPlaybackRefuseARecordingWithErrors) {
  const fs::path csv = dir_ / "recording" / "frames.csv";
  std::string text = ReadAll(csv.string());
  const size_t at = text.find("frames/000001.png");
  text.replace(at, 17, "frames/../../x.png");
  std::ofstream(csv, std::ios::binary | std::ios::trunc) << text;
  std::ostringstream out, err;
  PlaybackArgs playback;
  playback.recording = (dir_ / "recording").string();
  playback.out_dir = (dir_ / "pb").string();
  try {
    RunPlayback(playback, {out, err});
    FAIL() << "playback of a recording with errors";
  } catch (const CheckFailedError& e) {
    EXPECT_NE(std::string(e.what()).find("frames.csv:3"), std::string::npos) << e.what();
  }
  FitArgs fit;
  fit.recording = playback.recording;
  fit.out = (dir_ / "fit" / "model.yaml").string();
  EXPECT_THROW(RunFit(fit, {out, err}), CheckFailedError);
  EXPECT_FALSE(fs::exists(dir_ / "fit" / "model.yaml"));
}

// The issue: fit on a recording a live calibrate was writing only warned, and wrote into the
// live folder. Now it refuses while the writer (or the run) holds its lock, and writes nothing.
TEST_F(OfflineTest, FitRefusesARecordingALiveRunIsWriting) {
  std::ostringstream out, err;
  FitArgs fit;
  fit.recording = (dir_ / "recording").string();
  {
    auto live = RecordingWriter::Resume(fit.recording);
    try {
      RunFit(fit, {out, err});
      FAIL() << "fit beside a live writer";
    } catch (const RunFolderError& e) {
      EXPECT_NE(std::string(e.what()).find("process " + std::to_string(getpid())),
                std::string::npos) << e.what();
    }
    live->Close(Completion::kCut);
  }
  {
    const RunFolderLock live(dir_.string(), "calibrate");  // recording done, processing
    EXPECT_THROW(RunFit(fit, {out, err}), RunFolderError);
  }
  EXPECT_FALSE(fs::exists(dir_ / "model.yaml"));
  EXPECT_FALSE(fs::exists(dir_ / "features.csv"));
}

// A result that is a link is never written through, --force or not.
TEST_F(OfflineTest, FitAndPlaybackNeverWriteThroughALinkedResult) {
  const fs::path victim = dir_.string() + "-victim";
  std::ofstream(victim) << "precious\n";
  fs::create_symlink(victim, dir_ / "features.csv");
  std::ostringstream out, err;
  PlaybackArgs playback;
  playback.recording = (dir_ / "recording").string();
  playback.force = true;
  try {
    RunPlayback(playback, {out, err});
    FAIL() << "playback wrote through a linked features.csv";
  } catch (const RunFolderError& e) {
    EXPECT_NE(std::string(e.what()).find((dir_ / "features.csv").string() + " is a symbolic link"),
              std::string::npos) << e.what();
  }
  FitArgs fit;
  fit.recording = playback.recording;
  fit.force = true;
  EXPECT_THROW(RunFit(fit, {out, err}), RunFolderError);
  EXPECT_EQ(ReadAll(victim.string()), "precious\n");
  fs::remove(victim);
}

// Two frames swapped (the issue: fit then exited 0 with 10-18% model errors): refused, naming
// the frame.
TEST_F(OfflineTest, FitAndPlaybackRefuseSwappedFrames) {
  const fs::path a = dir_ / "recording/frames/000000.png";
  const fs::path b = dir_ / "recording/frames/000001.png";
  const fs::path tmp = dir_ / "swap.png";
  fs::rename(a, tmp);
  fs::rename(b, a);
  fs::rename(tmp, b);
  std::ostringstream out, err;
  FitArgs fit;
  fit.recording = (dir_ / "recording").string();
  fit.out = (dir_ / "fit" / "model.yaml").string();
  try {
    RunFit(fit, {out, err});
    FAIL() << "fit of swapped frames";
  } catch (const CheckFailedError& e) {
    EXPECT_NE(std::string(e.what()).find("frames/000000.png: its content is not the frame"),
              std::string::npos) << e.what();
  }
  PlaybackArgs playback;
  playback.recording = fit.recording;
  playback.out_dir = (dir_ / "pb").string();
  EXPECT_THROW(RunPlayback(playback, {out, err}), CheckFailedError);
}

// Model fitness: each weakness of a model is a named warning, none for a complete one.
TEST(ModelFitness, NamesABlankSerialAMissingProvenanceAndNoFingerprint) {
  CalibrationModel model;
  const auto names = [](const std::vector<std::string>& warnings) {
    std::string all;
    for (const std::string& w : warnings) all += w + "\n";
    return all;
  };
  std::string text = names(ModelFitnessWarnings(model, "m.yaml"));
  EXPECT_NE(text.find("model fitness (no_provenance): m.yaml"), std::string::npos) << text;
  EXPECT_NE(text.find("model fitness (no_fingerprint)"), std::string::npos) << text;
  model.provenance.known = true;
  text = names(ModelFitnessWarnings(model, "m.yaml"));
  EXPECT_NE(text.find("model fitness (blank_serial)"), std::string::npos) << text;
  EXPECT_EQ(text.find("no_provenance"), std::string::npos) << text;
  model.provenance.camera_serial = "IRDV0001";
  model.blur_calibration.noise_at_1m_px2 = 0.01;
  EXPECT_TRUE(ModelFitnessWarnings(model, "m.yaml").empty());
}

// The optics fingerprint: named when the first assessed bracket's blur is not the model's.
TEST(ModelFitness, OpticsFingerprintWarnsOnlyWhenTheFirstCheckIsFlagged) {
  CalibrationModel model;
  model.ranges.d_min_mm = 1500.0;
  model.ranges.d_max_mm = 3000.0;
  HealthCheck h;
  h.assessed = true;
  h.blur_var_px2 = 0.9;
  h.calibrated_px2 = 0.57;
  EXPECT_EQ(OpticsFingerprintWarning(model, h, 2000.0), "");
  h.flagged = true;
  const std::string w = OpticsFingerprintWarning(model, h, 2000.0);
  EXPECT_NE(w.find("model fitness (optics_differ)"), std::string::npos) << w;
  EXPECT_NE(w.find("1500 mm"), std::string::npos) << w;
  EXPECT_NE(w.find("2250 mm"), std::string::npos) << w;
  EXPECT_NE(w.find("recalibrate"), std::string::npos) << w;
}

}  // namespace
}  // namespace irdist
