// The scene pass's segmentation: other blobs found, masked or named (estimator/scene.h, part 2).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "estimator/scene.h"
#include "estimator/scene_internal.h"
#include "estimator/window_scan.h"

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

// The pixels of component `b` (frame coordinates) with a 4-neighbour outside it (or outside the
// frame): the only ones that can be nearest to a pixel of another component (from an inner pixel,
// the neighbour towards that pixel is nearer).
std::vector<cv::Point> EdgePixelsOf(const cv::Mat& labels, const Blob& b) {
  std::vector<cv::Point> out;
  const auto in = [&](int x, int y) {
    return x >= 0 && y >= 0 && x < labels.cols && y < labels.rows &&
           labels.at<int32_t>(y, x) == b.label;
  };
  for (int y = b.rect.y; y < b.rect.br().y; ++y) {
    const int32_t* label = labels.ptr<int32_t>(y);
    for (int x = b.rect.x; x < b.rect.br().x; ++x) {
      if (label[x] != b.label) continue;
      if (!in(x - 1, y) || !in(x + 1, y) || !in(x, y - 1) || !in(x, y + 1)) out.emplace_back(x, y);
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
// (their edge pixels') less one (touching pixels give 0). Far apart (beyond `near_px`), the boxes'
// gap.
double EdgeGap(const cv::Mat& labels, const Blob& a, const Blob& b, double near_px) {
  const double boxes = RectGap(a.rect, b.rect);
  if (boxes > near_px) return boxes;
  const std::vector<cv::Point> pa = EdgePixelsOf(labels, a), pb = EdgePixelsOf(labels, b);
  double best2 = std::numeric_limits<double>::infinity();
  for (const cv::Point& p : pa) {
    for (const cv::Point& q : pb) {
      const double dx = p.x - q.x, dy = p.y - q.y;
      best2 = std::min(best2, dx * dx + dy * dy);
    }
  }
  return std::max(0.0, std::sqrt(best2) - 1.0);
}

// Mean gray level of the pixels of `ring` (255) that belong to no component (image, labels and
// ring: views of one box): the local background
// (the mean, not the median: a fill at the median of a quantised, skewed noise biases E_rel).
double LocalBackground(const cv::Mat& image, const cv::Mat& labels, const cv::Mat& ring,
                       double fallback) {
  double sum = 0.0;
  int n = 0;
  for (int y = 0; y < ring.rows; ++y) {
    for (int x = 0; x < ring.cols; ++x) {
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
void FillAtLevel(const cv::Mat& mask, double level, cv::Mat image) {  // a view of mask's box
  std::vector<cv::Point> pixels;
  cv::findNonZero(mask, pixels);
  double acc = 0.0;
  for (const cv::Point& p : pixels) {
    const double before = std::floor(acc);
    acc += level;
    image.at<uint16_t>(p) = static_cast<uint16_t>(std::floor(acc) - before);
  }
}

// The square window of `side` px centred on `c` (as the features place it).
cv::Rect WindowAround(cv::Point2d c, int side) {
  return cv::Rect(static_cast<int>(std::lround(c.x - 0.5 * (side - 1))),
                  static_cast<int>(std::lround(c.y - 0.5 * (side - 1))), side, side);
}

// The pixels above `threshold`, in row order, each row scanned only when it holds one (most
// rows of a frame hold none: estimator/window_scan.h LevelAbove).
std::vector<cv::Point> PixelsAbove(const cv::Mat& image, double threshold) {
  std::vector<cv::Point> out;
  const LevelAbove above(threshold);
  for (int y = 0; y < image.rows; ++y) {
    const uint16_t* row = image.ptr<uint16_t>(y);
    if (!above.AnyIn(row, image.cols)) continue;
    for (int x = 0; x < image.cols; ++x) {
      if (above(row[x])) out.emplace_back(x, y);
    }
  }
  return out;
}

int Root(std::vector<int>* parent, int i) {
  while ((*parent)[i] != i) i = (*parent)[i] = (*parent)[(*parent)[i]];
  return i;
}

// 8-connected components of a frame's few set pixels (row order) (a frame's blobs and specks: hundreds of
// pixels among tens of thousands), by union-find over them in row order; labels 1..n in *labels
// (CV_32S, frame-sized), one Blob (label, box, area) each. cv::connectedComponentsWithStats
// scans the whole frame, 5-10x slower on a 256 x 256 ROI with a few scattered hot pixels.
std::vector<Blob> LabelSparse(const std::vector<cv::Point>& set, cv::Size size, cv::Mat* labels) {
  *labels = cv::Mat::zeros(size, CV_32S);
  std::vector<int> parent = {0};
  for (const cv::Point& p : set) {
    int label = 0;
    for (const cv::Point& d : {cv::Point(-1, 0), cv::Point(-1, -1), cv::Point(0, -1), cv::Point(1, -1)}) {
      const cv::Point q = p + d;
      if (q.x < 0 || q.y < 0 || q.x >= size.width) continue;
      const int n = labels->at<int32_t>(q);
      if (n == 0) continue;
      const int root = Root(&parent, n);
      if (label == 0) {
        label = root;
      } else if (root != label) {
        parent[std::max(root, label)] = std::min(root, label);
        label = std::min(root, label);
      }
    }
    if (label == 0) {
      label = static_cast<int>(parent.size());
      parent.push_back(label);
    }
    labels->at<int32_t>(p) = label;
  }
  std::vector<int> compact(parent.size(), 0);
  std::vector<Blob> blobs;
  for (const cv::Point& p : set) {
    const int root = Root(&parent, labels->at<int32_t>(p));
    if (compact[root] == 0) {
      compact[root] = static_cast<int>(blobs.size()) + 1;
      blobs.emplace_back();
      blobs.back().label = compact[root];
      blobs.back().rect = cv::Rect(p, cv::Size(1, 1));
    }
    Blob& b = blobs[compact[root] - 1];
    labels->at<int32_t>(p) = b.label;
    b.rect |= cv::Rect(p, cv::Size(1, 1));
    ++b.area;
  }
  return blobs;
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
  out.blobs = LabelSparse(PixelsAbove(image, out.threshold), image.size(), &out.labels);
  MeasureBlobs(image, out.labels, noise.background, &out.blobs);
  out.ired = PickIred(out.blobs, options, context);
  return out;
}

void ForgetDefects(const cv::Mat& cleaned, const std::vector<cv::Point>& defects,
                   const SceneOptions& options, const SceneContext& context, Segments* segments) {
  if (segments->blobs.empty()) return;
  for (const cv::Point& p : defects) {
    int32_t& label = segments->labels.at<int32_t>(p);
    if (label == 0 || cleaned.at<uint16_t>(p) > segments->threshold) continue;
    for (Blob& b : segments->blobs) {
      if (b.label == label) --b.area;
    }
    label = 0;
  }
  std::vector<Blob> kept;
  for (Blob b : segments->blobs) {
    if (b.area <= 0) continue;
    b.flux = 0.0;
    kept.push_back(b);
  }
  segments->blobs = kept;
  MeasureBlobs(cleaned, segments->labels, segments->background, &segments->blobs);
  segments->ired = PickIred(segments->blobs, options, context);
}

LocalMask GrownMask(const Segments& segments, const Blob& b, double reach_px, cv::Size frame) {
  const int r = static_cast<int>(std::ceil(reach_px));
  LocalMask out;
  out.box = cv::Rect(b.rect.x - r, b.rect.y - r, b.rect.width + 2 * r, b.rect.height + 2 * r) &
            cv::Rect(cv::Point(0, 0), frame);
  cv::compare(segments.labels(out.box), cv::Scalar(b.label), out.mask, cv::CMP_EQ);
  if (r > 0) {
    const cv::Mat disc =
        cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * r + 1, 2 * r + 1));
    cv::dilate(out.mask, out.mask, disc);
  }
  return out;
}

void MaskOtherBlobs(const Segments& segments, const SceneOptions& options,
                    const SceneContext& context, cv::Mat* image, SceneReport* report) {
  const Blob& ired = segments.blobs[static_cast<std::size_t>(segments.ired)];
  const cv::Size frame = image->size();
  const LocalMask ired_reach = GrownMask(segments, ired, options.halo_reach_px, frame);
  const cv::Rect window = WindowAround(ired.centroid, context.window_side_px);
  const cv::Mat original = image->clone();
  for (std::size_t i = 0; i < segments.blobs.size(); ++i) {
    const Blob& b = segments.blobs[i];
    if (static_cast<int>(i) == segments.ired) continue;
    LocalMask grown = GrownMask(segments, b, options.halo_reach_px, frame);
    if (b.area >= options.min_blob_area_px) {
      const double gap = EdgeGap(segments.labels, ired, b, 4.0 * options.halo_reach_px + 8.0);
      if (!(gap >= report->second_source_gap_px)) report->second_source_gap_px = gap;
      if (gap < 2.0 * options.halo_reach_px) report->second_source = true;
      if ((grown.box & window).area() > 0) {
        ++report->other_blobs;
        report->other_blob_rects.push_back(b.rect);
      }
    }
    const cv::Rect shared = grown.box & ired_reach.box;  // the IRED's own light is never masked
    if (!shared.empty()) {
      grown.mask(shared - grown.box.tl()).setTo(0, ired_reach.mask(shared - ired_reach.box.tl()));
    }
    LocalMask ring = GrownMask(segments, b, options.halo_reach_px + 2.0, frame);
    ring.mask(grown.box - ring.box.tl()).setTo(0, grown.mask);
    const double level =
        LocalBackground(original(ring.box), segments.labels(ring.box), ring.mask,
                        segments.background);
    FillAtLevel(grown.mask, level, (*image)(grown.box));
  }
}

}  // namespace irdist::scene
