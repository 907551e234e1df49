// The scene pass's noise model and defect pixels (estimator/scene.h, parts 1).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "estimator/scene.h"
#include "estimator/scene_internal.h"

namespace irdist::scene {
namespace {

// Quantisation alone (a noise-free frame) still moves a pixel by up to half a gray level.
constexpr double kMinReadSd = 0.5;
// The background and the read noise from every kNoiseRowStride-th row, a pair of neighbours in
// each two columns (a 256 px frame: 8k pairs).
constexpr int kNoiseRowStride = 4;
// A plateau needs this many interior pixels to measure the shot noise on.
constexpr int kMinPlateauPixels = 16;

// The q-quantile of integer samples held as a histogram, each integer k spread uniformly over
// [k - 0.5, k + 0.5] (clipped at 0): a sub-gray-level median of quantised values.
double HistogramQuantile(const std::vector<int>& histogram, double q) {
  long total = 0;
  for (int n : histogram) total += n;
  if (total == 0) return 0.0;
  const double target = q * static_cast<double>(total);
  double below = 0.0;
  for (std::size_t k = 0; k < histogram.size(); ++k) {
    const double n = histogram[k];
    if (n > 0.0 && below + n >= target) {
      const double lo = k == 0 ? 0.0 : k - 0.5, hi = k + 0.5;
      return lo + (hi - lo) * (target - below) / n;
    }
    below += n;
  }
  return static_cast<double>(histogram.size() - 1);
}

// The 8 neighbours of (x, y), x and y at least 1 from the frame's border.
void Neighbours(const cv::Mat& image, int x, int y, double n[8]) {
  const uint16_t* up = image.ptr<uint16_t>(y - 1);
  const uint16_t* mid = image.ptr<uint16_t>(y);
  const uint16_t* down = image.ptr<uint16_t>(y + 1);
  n[0] = up[x - 1], n[1] = up[x], n[2] = up[x + 1], n[3] = mid[x - 1];
  n[4] = mid[x + 1], n[5] = down[x - 1], n[6] = down[x], n[7] = down[x + 1];
}

// The 8 values in descending order (insertion: 8 values).
void SortDescending(double n[8]) {
  for (int i = 1; i < 8; ++i) {
    const double v = n[i];
    int j = i;
    for (; j > 0 && n[j - 1] < v; --j) n[j] = n[j - 1];
    n[j] = v;
  }
}

// A thin line (a cable's shadow, the valley between two blobs) is not a defect: its pixels have
// two neighbours on roughly opposite sides (135-225 deg apart around them, any line's direction)
// near their own value, where a defect's neighbours all sit near the median.
bool OnALine(double g, const double n[8], double m, double sd) {
  // Neighbours' order (Neighbours) to their order around the pixel.
  constexpr int kAround[8] = {0, 1, 2, 4, 7, 6, 5, 3};
  const double near = 0.5 * std::abs(g - m) + sd;
  bool close[8];
  for (int k = 0; k < 8; ++k) close[k] = std::abs(n[kAround[k]] - g) < near;
  for (int k = 0; k < 8; ++k) {
    if (close[k] && (close[(k + 3) % 8] || close[(k + 4) % 8] || close[(k + 5) % 8])) return true;
  }
  return false;
}

// Whether gray level g with neighbours n (Neighbours' order), the same sorted descending, and the
// 3x3 median m is a defect: brighter than all but one neighbour, or darker than all but one, by
// defect_sigmas noise sd (a pair of hot pixels is each other's brightest neighbour); or away from
// the median by that much beyond the share of the neighbours' range an edge's curvature allows,
// and not on a line.
bool IsDefect(double g, const double n[8], const double sorted[8], double m,
              const NoiseModel& noise, const SceneOptions& options) {
  const double k = options.defect_sigmas;
  if (g - sorted[1] > k * noise.Sd(sorted[1])) return true;
  if (sorted[6] - g > k * noise.Sd(sorted[6])) return true;
  const double allowance = options.defect_edge_allowance * (sorted[1] - sorted[6]);
  return std::abs(g - m) > k * noise.Sd(m) + allowance && !OnALine(g, n, m, noise.Sd(g));
}

// The set pixels of a CV_8U mask in row order (cv::findNonZero's points and order): each row
// tested whole first (a loop the compiler vectorises), as most rows of a frame hold none.
std::vector<cv::Point> SetPixels(const cv::Mat& mask) {
  std::vector<cv::Point> out;
  for (int y = 0; y < mask.rows; ++y) {
    const uint8_t* row = mask.ptr<uint8_t>(y);
    uint8_t any = 0;
    for (int x = 0; x < mask.cols; ++x) any |= row[x];
    if (any == 0) continue;
    for (int x = 0; x < mask.cols; ++x) {
      if (row[x] != 0) out.emplace_back(x, y);
    }
  }
  return out;
}

}  // namespace

double NoiseModel::Sd(double level) const {
  return std::sqrt(read_sd * read_sd + shot_gain * std::max(0.0, level - background));
}

NoiseModel MeasureBackgroundNoise(const cv::Mat& image, int bit_depth) {
  const int levels = 1 << bit_depth;
  std::vector<int> gray(static_cast<std::size_t>(levels), 0);
  std::vector<int> step(1024, 0);
  for (int y = 0; y < image.rows; y += kNoiseRowStride) {
    const uint16_t* row = image.ptr<uint16_t>(y);
    for (int x = 0; x + 1 < image.cols; x += 2) {  // pairs of neighbours
      ++gray[std::min<int>(row[x], levels - 1)];
      ++step[std::min(std::abs(row[x + 1] - row[x]), 1023)];
    }
  }
  NoiseModel noise;
  noise.background = HistogramQuantile(gray, 0.5);
  // |a - b| of two pixels of sd s has median 0.6745 sqrt(2) s.
  noise.read_sd = std::max(kMinReadSd, HistogramQuantile(step, 0.5) / (0.6745 * std::sqrt(2.0)));
  return noise;
}

void MeasureShotGain(const cv::Mat& image, const cv::Mat& median3, int bit_depth,
                     double fallback_dn, NoiseModel* noise) {
  noise->shot_gain = fallback_dn * ((1 << bit_depth) - 1) / 4095.0;
  double top = 0.0;
  cv::Point at;
  cv::minMaxLoc(median3, nullptr, &top, nullptr, &at);
  const double floor = noise->background + 0.7 * (top - noise->background);
  if (!(top - noise->background > 10.0 * noise->read_sd)) return;
  const cv::Rect box = cv::Rect(at.x - 24, at.y - 24, 49, 49) &
                       cv::Rect(1, 1, image.cols - 2, image.rows - 2);
  cv::Mat interior;  // the 3x3 minimum of the median: all of a pixel's neighbours on the plateau
  cv::erode(median3(box + cv::Size(2, 2) - cv::Point(1, 1)), interior, cv::Mat());
  std::vector<double> departures, levels;
  double n[8];
  for (int y = box.y; y < box.br().y; ++y) {
    const uint16_t* inside = interior.ptr<uint16_t>(y - box.y + 1);
    for (int x = box.x; x < box.br().x; ++x) {
      if (inside[x - box.x + 1] <= floor) continue;
      Neighbours(image, x, y, n);
      const double g = image.at<uint16_t>(y, x);
      departures.push_back(g - 0.25 * (n[1] + n[3] + n[4] + n[6]));
      levels.push_back(g);
    }
  }
  if (static_cast<int>(departures.size()) < kMinPlateauPixels) return;
  std::vector<double> spread = departures;
  const auto mid = spread.begin() + spread.size() / 2;
  std::nth_element(spread.begin(), mid, spread.end());
  const double centre = *mid;
  for (double& d : spread) d = std::abs(d - centre);
  std::nth_element(spread.begin(), mid, spread.end());
  const double var = std::pow(1.4826 * *mid, 2) / 1.25;  // g - mean of 4: 1 + 1/4 variances
  std::nth_element(levels.begin(), levels.begin() + levels.size() / 2, levels.end());
  const double signal = levels[levels.size() / 2] - noise->background;
  noise->shot_gain = std::max(0.0, (var - noise->read_sd * noise->read_sd) / signal);
}

cv::Mat DetectDefects(const cv::Mat& image, const cv::Mat& median3, const NoiseModel& noise,
                      const SceneOptions& options) {
  cv::Mat mask = cv::Mat::zeros(image.size(), CV_8U);
  // Every defect departs from the 3x3 median by defect_sigmas read-noise sd at least: the cheap
  // screen before the per-pixel test.
  cv::Mat departure, candidates;
  cv::absdiff(image, median3, departure);
  cv::compare(departure, cv::Scalar(options.defect_sigmas * noise.read_sd), candidates,
              cv::CMP_GT);
  std::vector<cv::Point> screened;
  cv::findNonZero(candidates, screened);
  double n[8], sorted[8];
  for (const cv::Point& p : screened) {
    if (p.x < 1 || p.y < 1 || p.x >= image.cols - 1 || p.y >= image.rows - 1) continue;
    Neighbours(image, p.x, p.y, n);
    std::copy(n, n + 8, sorted);
    SortDescending(sorted);
    if (IsDefect(image.at<uint16_t>(p), n, sorted, median3.at<uint16_t>(p), noise, options)) {
      mask.at<uint8_t>(p) = 255;
    }
  }
  return mask;
}

void AddKnownDefects(const DefectMap& map, cv::Point roi_origin, cv::Mat* mask) {
  for (const cv::Point& sensor : map.sensor_px) {
    const cv::Point p = sensor - roi_origin;
    if (p.x >= 0 && p.y >= 0 && p.x < mask->cols && p.y < mask->rows) mask->at<uint8_t>(p) = 255;
  }
}

void ReplaceDefects(const cv::Mat& mask, cv::Mat* image, std::vector<cv::Point>* where) {
  const std::vector<cv::Point> defects = SetPixels(mask);
  const cv::Mat original = image->clone();
  for (const cv::Point& p : defects) {
    double good[8], all[8];
    int count = 0, n_all = 0;
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        const cv::Point q(p.x + dx, p.y + dy);
        if ((dx == 0 && dy == 0) || q.x < 0 || q.y < 0 || q.x >= mask.cols || q.y >= mask.rows) {
          continue;
        }
        all[n_all++] = original.at<uint16_t>(q);
        if (mask.at<uint8_t>(q) == 0) good[count++] = original.at<uint16_t>(q);
      }
    }
    double* values = count > 0 ? good : all;
    const int n = count > 0 ? count : n_all;
    std::sort(values, values + n);
    const double value = n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
    image->at<uint16_t>(p) = static_cast<uint16_t>(std::lround(value));
    where->push_back(p);
  }
}

}  // namespace irdist::scene
