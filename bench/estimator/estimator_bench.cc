// Speed of the estimator's per-frame work: features on a 1280x1024 16-bit frame, and one
// Algorithm 1 estimate (one pair, and a 4-exposure bracket); the estimation default's features
// (moments, then the blob's likelihood fit with the calibrated blur), against the moments alone.
#include <benchmark/benchmark.h>

#include <opencv2/imgproc.hpp>

#include "estimator/blob_fit.h"
#include "estimator/estimate.h"
#include "estimator/features.h"
#include "estimator/refocus.h"
#include "estimator/scene.h"
#include "tests/estimator/ringing_table.h"
#include "tests/estimator/scene_render.h"
#include "tests/estimator/synthetic.h"

namespace irdist {
namespace {

cv::Mat Frame() {
  cv::Mat frame(1024, 1280, CV_32F, cv::Scalar(0.02));
  cv::ellipse(frame, cv::Point(700, 480), cv::Size(15, 12), 30.0, 0, 360, cv::Scalar(0.6),
              cv::FILLED);
  cv::GaussianBlur(frame, frame, cv::Size(0, 0), 1.0);
  cv::Mat noise(frame.size(), CV_32F);
  cv::randn(noise, 0.0, 0.002);
  frame += noise;
  cv::Mat out;
  frame.convertTo(out, CV_16U, 4095.0);
  return out;
}

void BM_ComputeFeatures(benchmark::State& state) {
  const cv::Mat frame = Frame();
  FeatureOptions options;
  options.roi_policy = static_cast<RoiPolicy>(state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(ComputeFeatures(frame, 12, options));
}
BENCHMARK(BM_ComputeFeatures)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

// What the app's estimation default costs per frame (app/processing/frame_features.h
// FrameFeatures with a model, as playback --model runs it): the moments, then FitBlob with the frame's blur (sigma 1 px, pixel area added). Compare
// with BM_ComputeFeatures/0 of the same run.
void BM_FeaturesWithBlobFit(benchmark::State& state) {
  const cv::Mat frame = Frame();
  const FeatureOptions options;
  const double blur_var_px2 = 1.0 + 1.0 / 12.0;
  for (auto _ : state) {
    const Features features = ComputeFeatures(frame, 12, options);
    benchmark::DoNotOptimize(FitBlob(frame, 12, features, blur_var_px2));
  }
}
BENCHMARK(BM_FeaturesWithBlobFit)->Unit(benchmark::kMicrosecond);

// The blob fit alone on the same frame (its features computed once): BM_FeaturesWithBlobFit less
// BM_ComputeFeatures/0, measured directly.
void BM_BlobFitOnly(benchmark::State& state) {
  const cv::Mat frame = Frame();
  const Features features = ComputeFeatures(frame, 12, FeatureOptions());
  const double blur_var_px2 = 1.0 + 1.0 / 12.0;
  for (auto _ : state) benchmark::DoNotOptimize(FitBlob(frame, 12, features, blur_var_px2));
}
BENCHMARK(BM_BlobFitOnly)->Unit(benchmark::kMicrosecond);

// The scene pass (estimator/scene.h) per frame at a 256 x 256 ROI, beside ComputeFeatures on the
// same frame (goal: the pass at most 20 % of it): a clean frame (Arg 0), and one with 30 hot
// pixels and a reflection 15 px from the disc (Arg 1).
cv::Mat RoiFrame(bool cluttered) {
  std::mt19937_64 rng(42);
  testing::SceneDisc disc;
  disc.cx = 127.4, disc.cy = 121.8, disc.a = 8.0, disc.b = 7.4, disc.angle_deg = 25.0;
  std::vector<testing::SceneDisc> discs = {disc};
  if (cluttered) {
    testing::SceneDisc reflection = disc;
    reflection.cy += 31.0;
    reflection.amplitude_e *= 0.2;
    discs.push_back(reflection);
  }
  cv::Mat frame = testing::SensorFrame(testing::RenderScene(256, 50.0, discs, 0.7),
                                       testing::NormalField(256, &rng));
  std::uniform_int_distribution<int> at(2, 253), level(2457, 4095);
  for (int i = 0; cluttered && i < 30; ++i) {
    frame.at<std::uint16_t>(at(rng), at(rng)) = static_cast<std::uint16_t>(level(rng));
  }
  return frame;
}

void BM_RoiComputeFeatures(benchmark::State& state) {
  const cv::Mat frame = RoiFrame(state.range(0) != 0);
  const FeatureOptions options;
  for (auto _ : state) benchmark::DoNotOptimize(ComputeFeatures(frame, 12, options));
}
BENCHMARK(BM_RoiComputeFeatures)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

// The estimation default's per-frame cost on a live ROI (256 x 256, the default 64 px window),
// as app/processing/frame_features.cc runs it: the scene pass, the moments, then FitBlob with the
// frame's blur (the rendering's 0.7 px optics, pixel area added); a clean frame (Arg 0) and a
// cluttered one (Arg 1). The figure tracking needs (<= 1.5 ms a frame).
void BM_RoiFrameWithBlobFit(benchmark::State& state) {
  const cv::Mat frame = RoiFrame(state.range(0) != 0);
  const FeatureOptions options;
  const double blur_var_px2 = 0.7 * 0.7 + 1.0 / 12.0;
  for (auto _ : state) {
    const SceneFrame cleaned = CleanScene(frame, 12, options.scene);
    const Features features = ComputeFeatures(cleaned.image, 12, options);
    const BlobFitResult fit = FitBlob(cleaned.image, 12, features, blur_var_px2);
    if (!fit.ok) state.SkipWithError("the blob fit failed");
    benchmark::DoNotOptimize(fit);
  }
}
BENCHMARK(BM_RoiFrameWithBlobFit)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

// The same clean frame as a live frame meets the host: a new copy each time, and the caches
// evicted before it (a tracking frame arrives after about 20 ms of other work). Arg: the steps
// timed (0 all three, 1 the scene pass, 2 the moments, 3 the blob fit).
void BM_RoiFrameCold(benchmark::State& state) {
  const cv::Mat frame = RoiFrame(false);
  const FeatureOptions options;
  const double blur_var_px2 = 0.7 * 0.7 + 1.0 / 12.0;
  std::vector<char> evict(64 << 20, 1);
  const int timed = static_cast<int>(state.range(0));
  using Clock = std::chrono::steady_clock;
  for (auto _ : state) {
    for (std::size_t i = 0; i < evict.size(); i += 64) evict[i] = static_cast<char>(evict[i] + 1);
    const cv::Mat arrived = frame.clone();
    const auto t0 = Clock::now();
    const SceneFrame cleaned = CleanScene(arrived, 12, options.scene);
    const auto t1 = Clock::now();
    const Features features = ComputeFeatures(cleaned.image, 12, options);
    const auto t2 = Clock::now();
    const BlobFitResult fit = FitBlob(cleaned.image, 12, features, blur_var_px2);
    const auto t3 = Clock::now();
    benchmark::DoNotOptimize(fit);
    const Clock::time_point from[] = {t0, t0, t1, t2}, to[] = {t3, t1, t2, t3};
    state.SetIterationTime(std::chrono::duration<double>(to[timed] - from[timed]).count());
  }
}
BENCHMARK(BM_RoiFrameCold)->Arg(0)->Arg(1)->Arg(2)->Arg(3)->UseManualTime()->Unit(
    benchmark::kMicrosecond);

// The blob fit alone on the live ROI's clean frame, without crosstalk (Arg 0) and with the small
// crosstalk a Table 3 calibration of the virtual rig fits (Arg 1: 0.0015 px^2, its kernel spread
// over the model's six planes each evaluation), and a sharp lens with almost all of the same blur
// after the pixels (Arg 2: 0.48 px^2 of crosstalk, optics of 0.1 px sd, where each edge pixel's
// square is its four half-squares, estimator/blob_pixel_model.cc), and Arg 0's optics with a
// defocus disc's flat-topped edge (Arg 3: excess kurtosis -2, the Gram-Charlier term), and an
// Airy pattern's edge at the family's end with an edge correction (Arg 4: excess 4 and a table of
// a ringing of 0.01 of the brightness, estimator/edge_correction.h: each pixel within 5 px of the
// edge takes it and its derivatives); and the frame's own blur at the calibrated blur
// (estimator/refocus.h MeasureOwnBlur: one profile, ProfileBlobBlur), which measure and playback
// add to every refined frame.
Crosstalk RoiCrosstalk(int arg) {
  return arg == 0   ? Crosstalk()
         : arg == 1 ? Crosstalk(0.0015, 0.002)
         : arg == 2 ? Crosstalk(0.48, 0.0)
         : arg == 3 ? Crosstalk(0.0, 0.0, -2.0)
                    : Crosstalk(0.0, 0.0, 4.0, testing::RingingEdgeCorrection(0.01));
}

void BM_RoiBlobFit(benchmark::State& state) {
  const cv::Mat frame = RoiFrame(false);
  const Features features = ComputeFeatures(frame, 12, FeatureOptions());
  const double blur_var_px2 = 0.7 * 0.7 + 1.0 / 12.0;
  const Crosstalk crosstalk = RoiCrosstalk(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    benchmark::DoNotOptimize(FitBlob(frame, 12, features, blur_var_px2, crosstalk));
  }
}
BENCHMARK(BM_RoiBlobFit)->Arg(0)->Arg(1)->Arg(2)->Arg(3)->Arg(4)->Unit(benchmark::kMicrosecond);

void BM_RoiOwnBlur(benchmark::State& state) {
  const cv::Mat frame = RoiFrame(false);
  const Features start = ComputeFeatures(frame, 12, FeatureOptions());
  const double blur_var_px2 = 0.7 * 0.7 + 1.0 / 12.0;
  CalibrationModel model;
  const Crosstalk crosstalk = RoiCrosstalk(static_cast<int>(state.range(0)));
  model.blur_calibration.crosstalk_var_px2 = crosstalk.var_px2;
  model.blur_calibration.crosstalk_lattice_share = crosstalk.lattice_share;
  model.blur_calibration.optics_excess = crosstalk.optics_excess;
  Features refined = start;
  const BlobFitResult fit = FitBlob(frame, 12, start, blur_var_px2, crosstalk);
  refined.moment_major_var_px2 = fit.major_var_px2 + blur_var_px2;
  refined.moment_minor_var_px2 = fit.minor_var_px2 + blur_var_px2;
  refined.size_blur_var_px2 = blur_var_px2;
  for (auto _ : state) {
    Features f = refined;
    if (!MeasureOwnBlur(frame, 12, model, start, &f)) state.SkipWithError("no own blur");
    benchmark::DoNotOptimize(f);
  }
}
BENCHMARK(BM_RoiOwnBlur)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

void BM_RoiScenePass(benchmark::State& state) {
  const cv::Mat frame = RoiFrame(state.range(0) != 0);
  const SceneOptions options;
  for (auto _ : state) benchmark::DoNotOptimize(CleanScene(frame, 12, options));
}
BENCHMARK(BM_RoiScenePass)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

// The same on BM_ComputeFeatures' full 1280 x 1024 frame (compare with BM_ComputeFeatures/0).
void BM_ScenePass(benchmark::State& state) {
  const cv::Mat frame = Frame();
  const SceneOptions options;
  for (auto _ : state) benchmark::DoNotOptimize(CleanScene(frame, 12, options));
}
BENCHMARK(BM_ScenePass)->Unit(benchmark::kMicrosecond);

void BM_EstimatePair(benchmark::State& state) {
  const testing::SyntheticRig rig;
  const CalibrationModel model = rig.ExactModel();
  const Features ref = rig.Frame(8.0, 500.0, 2300.0, 20.0, 21.0);
  const Features meas = rig.Frame(32.0, 500.0, 2300.0, 20.0, 21.0);
  for (auto _ : state) {
    benchmark::DoNotOptimize(EstimatePair(model, ref, 8.0, meas, 32.0, EstimateOptions()));
  }
}
BENCHMARK(BM_EstimatePair)->Unit(benchmark::kMicrosecond);

void BM_EstimateBracket(benchmark::State& state) {
  const testing::SyntheticRig rig;
  const CalibrationModel model = rig.ExactModel();
  const Features ref = rig.Frame(8.0, 500.0, 2300.0, 20.0, 21.0);
  std::vector<Features> meas;
  const std::vector<double> t = {30.0, 32.0, 34.0, 36.0};
  for (double tn : t) meas.push_back(rig.Frame(tn, 500.0, 2300.0, 20.0, 21.0));
  for (auto _ : state) {
    benchmark::DoNotOptimize(EstimateBracket(model, ref, 8.0, meas, t, EstimateOptions()));
  }
}
BENCHMARK(BM_EstimateBracket)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace irdist

BENCHMARK_MAIN();
