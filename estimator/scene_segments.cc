// The scene pass's segmentation: other blobs found, masked or named (estimator/scene.h, part 2).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "estimator/scene.h"
#include "estimator/scene_internal.h"

namespace irdist::scene {
namespace {

// Flux and intensity centroid of each component over its bounding box.
void MeasureBlobs(const cv::Mat& image, const cv::Mat& labels, double background,
                  std::vector<Blob>* blobs) {
  for (Blob& b : *blobs) {
    double sx = 0.0, sy = 0.0;
    for (int y = b.rect.y; y < b.rect.br().y; ++y) {
      const int32_t* label = labels.ptr<int32_t>(y);
      const uint16_t* row = image.ptr<uint16_t>(y);
      for (int x = b.rect.x; x < b.rect.br().x; ++x) {
        if (label[x] != b.label) continue;
        const double w = row[x] - background;
        b.flux += w;
        sx += w * x;
        sy += w * y;
      }
    }
    if (b.flux > 0.0) b.centroid = cv::Point2d(sx / b.flux, sy / b.flux);
  }
}

// The IRED: the component nearest the expected centre when one is given, else the one of most
// flux; among those of min_blob_area_px at least. -1 when none.
int PickIred(const std::vector<Blob>& blobs, const SceneOptions& options,
             const SceneContext& context) {
  int best = -1;
  double best_score = -std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < blobs.size(); ++i) {
    const Blob& b = blobs[i];
    if (b.area < options.min_blob_area_px || !(b.flux > 0.0)) continue;
    const double score =
        context.has_expected_center
            ? -std::hypot(b.centroid.x - context.expected_center_px.x,
                          b.centroid.y - context.expected_center_px.y)
            : b.flux;
    if (score > best_score) {
      best_score = score;
      best = static_cast<int>(i);
    }
  }
  return best;
}

// The pixels of component `b` (frame coordinates).
std::vector<cv::Point> PixelsOf(const cv::Mat& labels, const Blob& b) {
  std::vector<cv::Point> out;
  for (int y = b.rect.y; y < b.rect.br().y; ++y) {
    const int32_t* label = labels.ptr<int32_t>(y);
    for (int x = b.rect.x; x < b.rect.br().x; ++x) {
      if (label[x] == b.label) out.emplace_back(x, y);
    }
  }
  return out;
}

// Gap between the bounding boxes (px between pixel centres, less one: adjacent boxes give 0).
double RectGap(const cv::Rect& a, const cv::Rect& b) {
  const int dx = std::max({0, b.x - a.br().x + 1, a.x - b.br().x + 1});
  const int dy = std::max({0, b.y - a.br().y + 1, a.y - b.br().y + 1});
  return std::max(0.0, std::hypot(dx, dy) - 1.0);
}

// Edge-to-edge gap (px) between two components: the least distance between their pixels' centres
// less one (touching pixels give 0). Far apart (beyond `near_px`), the boxes' gap.
double EdgeGap(const cv::Mat& labels, const Blob& a, const Blob& b, double near_px) {
  const double boxes = RectGap(a.rect, b.rect);
  if (boxes > near_px) return boxes;
  const std::vector<cv::Point> pa = PixelsOf(labels, a), pb = PixelsOf(labels, b);
  double best2 = std::numeric_limits<double>::infinity();
  for (const cv::Point& p : pa) {
    for (const cv::Point& q : pb) {
      const double dx = p.x - q.x, dy = p.y - q.y;
      best2 = std::min(best2, dx * dx + dy * dy);
    }
  }
  return std::max(0.0, std::sqrt(best2) - 1.0);
}

// Mean gray level of the pixels of `ring` (255) that belong to no component: the local background
// (the mean, not the median: a fill at the median of a quantised, skewed noise biases E_rel).
double LocalBackground(const cv::Mat& image, const cv::Mat& labels, const cv::Mat& ring,
                       const cv::Rect& box, double fallback) {
  double sum = 0.0;
  int n = 0;
  for (int y = box.y; y < box.br().y; ++y) {
    for (int x = box.x; x < box.br().x; ++x) {
      if (ring.at<uint8_t>(y, x) != 0 && labels.at<int32_t>(y, x) == 0) {
        sum += image.at<uint16_t>(y, x);
        ++n;
      }
    }
  }
  return n < 8 ? fallback : sum / n;
}

// The pixels of `mask` (255) set to `level` on average: each the integer step of a running sum,
// so the fill's mean is the level itself and not its rounding (300 pixels rounded by up to half
// a gray level each would move F(0,0) by a few 1e-4).
void FillAtLevel(const cv::Mat& mask, double level, cv::Mat* image) {
  std::vector<cv::Point> pixels;
  cv::findNonZero(mask, pixels);
  double acc = 0.0;
  for (const cv::Point& p : pixels) {
    const double before = std::floor(acc);
    acc += level;
    image->at<uint16_t>(p) = static_cast<uint16_t>(std::floor(acc) - before);
  }
}

// The square window of `side` px centred on `c` (as the features place it).
cv::Rect WindowAround(cv::Point2d c, int side) {
  return cv::Rect(static_cast<int>(std::lround(c.x - 0.5 * (side - 1))),
                  static_cast<int>(std::lround(c.y - 0.5 * (side - 1))), side, side);
}

}  // namespace

Segments Segment(const cv::Mat& image, const NoiseModel& noise, const SceneOptions& options,
                 const SceneContext& context) {
  Segments out;
  out.background = noise.background;
  double peak = 0.0;
  cv::minMaxLoc(image, nullptr, &peak);
  out.threshold = noise.background + std::max(options.segment_sigmas * noise.read_sd,
                                               options.segment_peak_fraction *
                                                   (peak - noise.background));
  cv::Mat mask, labels, stats, centroids;
  cv::compare(image, cv::Scalar(out.threshold), mask, cv::CMP_GT);
  // The components within the mask's bounding box only (most of a frame is background).
  const cv::Rect box = cv::boundingRect(mask);
  out.labels = cv::Mat::zeros(image.size(), CV_32S);
  if (box.empty()) return out;
  const int n = cv::connectedComponentsWithStats(mask(box), labels, stats, centroids, 8, CV_32S);
  labels.copyTo(out.labels(box));
  for (int label = 1; label < n; ++label) {
    Blob b;
    b.label = label;
    b.rect = cv::Rect(stats.at<int>(label, cv::CC_STAT_LEFT) + box.x,
                      stats.at<int>(label, cv::CC_STAT_TOP) + box.y,
                      stats.at<int>(label, cv::CC_STAT_WIDTH),
                      stats.at<int>(label, cv::CC_STAT_HEIGHT));
    b.area = stats.at<int>(label, cv::CC_STAT_AREA);
    out.blobs.push_back(b);
  }
  MeasureBlobs(image, out.labels, noise.background, &out.blobs);
  out.ired = PickIred(out.blobs, options, context);
  return out;
}

cv::Mat GrownMask(const Segments& segments, const Blob& b, double reach_px, cv::Size frame) {
  const int r = static_cast<int>(std::ceil(reach_px));
  const cv::Rect box =
      cv::Rect(b.rect.x - r, b.rect.y - r, b.rect.width + 2 * r, b.rect.height + 2 * r) &
      cv::Rect(cv::Point(0, 0), frame);
  cv::Mat out = cv::Mat::zeros(frame, CV_8U);
  cv::Mat local;
  cv::compare(segments.labels(box), cv::Scalar(b.label), local, cv::CMP_EQ);
  if (r > 0) {
    const cv::Mat disc = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * r + 1, 2 * r + 1));
    cv::dilate(local, local, disc);
  }
  local.copyTo(out(box));
  return out;
}

void MaskOtherBlobs(const Segments& segments, const SceneOptions& options,
                    const SceneContext& context, cv::Mat* image, SceneReport* report) {
  const Blob& ired = segments.blobs[static_cast<std::size_t>(segments.ired)];
  const cv::Size frame = image->size();
  const cv::Mat ired_reach = GrownMask(segments, ired, options.halo_reach_px, frame);
  const cv::Rect window = WindowAround(ired.centroid, context.window_side_px);
  const cv::Mat original = image->clone();
  for (std::size_t i = 0; i < segments.blobs.size(); ++i) {
    const Blob& b = segments.blobs[i];
    if (static_cast<int>(i) == segments.ired) continue;
    cv::Mat grown = GrownMask(segments, b, options.halo_reach_px, frame);
    const cv::Rect box = cv::boundingRect(grown);
    if (b.area >= options.min_blob_area_px) {
      const double gap = EdgeGap(segments.labels, ired, b, 4.0 * options.halo_reach_px + 8.0);
      if (!(gap >= report->second_source_gap_px)) report->second_source_gap_px = gap;
      if (gap < 2.0 * options.halo_reach_px) report->second_source = true;
      if ((box & window).area() > 0) {
        ++report->other_blobs;
        report->other_blob_rects.push_back(b.rect);
      }
    }
    grown.setTo(0, ired_reach);  // the IRED's own light is never masked
    cv::Mat ring = GrownMask(segments, b, options.halo_reach_px + 2.0, frame);
    ring.setTo(0, grown);
    const double level = LocalBackground(original, segments.labels, ring,
                                         cv::boundingRect(ring), segments.background);
    FillAtLevel(grown, level, image);
  }
}

}  // namespace irdist::scene
