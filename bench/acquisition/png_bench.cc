// PNG encoding of one camera frame (256 x 256, 12 bits in 16: a Gaussian spot on a dark, noisy
// background, as the virtual rig renders it) at zlib levels and strategies: time per frame and
// bytes per frame (counter "bytes", and "ratio" = bytes / raw bytes). The recording writes frames
// with the setting this measures fastest among lossless 16-bit PNGs
// (acquisition/recording_writer.cc).
//   bench_png
#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

namespace {

cv::Mat CameraLikeFrame() {
  cv::Mat noise(256, 256, CV_32F);
  cv::RNG rng(7);
  rng.fill(noise, cv::RNG::NORMAL, 64.0, 6.0);  // black level + read and shot noise, counts
  cv::Mat frame(256, 256, CV_16UC1);
  for (int y = 0; y < frame.rows; ++y) {
    for (int x = 0; x < frame.cols; ++x) {
      const double r2 = (x - 130.0) * (x - 130.0) + (y - 125.0) * (y - 125.0);
      const double spot = 3500.0 * std::exp(-r2 / (2.0 * 9.0 * 9.0));
      frame.at<std::uint16_t>(y, x) =
          cv::saturate_cast<std::uint16_t>(std::min(4095.0, spot + noise.at<float>(y, x)));
    }
  }
  return frame;
}

void BM_EncodePng(benchmark::State& state) {
  const cv::Mat frame = CameraLikeFrame();
  const std::vector<int> params = {cv::IMWRITE_PNG_COMPRESSION, static_cast<int>(state.range(0)),
                                   cv::IMWRITE_PNG_STRATEGY, static_cast<int>(state.range(1))};
  std::vector<uchar> png;
  for (auto _ : state) {
    png.clear();
    if (!cv::imencode(".png", frame, png, params)) state.SkipWithError("imencode failed");
    benchmark::DoNotOptimize(png.data());
  }
  state.counters["bytes"] = static_cast<double>(png.size());
  state.counters["ratio"] = static_cast<double>(png.size()) / (frame.total() * frame.elemSize());
}

}  // namespace

// Arguments: zlib level (0 = stored), strategy (0 default, 1 filtered, 2 Huffman only, 3 RLE).
BENCHMARK(BM_EncodePng)
    ->ArgNames({"level", "strategy"})
    ->Args({0, 0})
    ->Args({1, 0})
    ->Args({1, 2})
    ->Args({1, 3})
    ->Args({3, 0})
    ->Args({6, 0})
    ->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
