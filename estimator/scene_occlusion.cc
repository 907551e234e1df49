// The scene pass's look at the IRED's shape: a second source merged into it, and occlusion
// (estimator/scene.h, part 3). The half-maximum edge is found along rays from the blob's centroid
// (sub-pixel, bilinear) and an ellipse is fitted to it robustly: a clean disc (tilted up to
// 30 deg: axis ratio 0.87) keeps its edge within a few 0.01 px of the ellipse, a cut one does not.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "estimator/scene.h"
#include "estimator/scene_internal.h"

namespace irdist::scene {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kRayStepPx = 0.25;

double Bilinear(const cv::Mat& image, double x, double y) {
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  if (x0 < 0 || y0 < 0 || x0 + 1 >= image.cols || y0 + 1 >= image.rows) return 0.0;
  const double fx = x - x0, fy = y - y0;
  const uint16_t* r0 = image.ptr<uint16_t>(y0);
  const uint16_t* r1 = image.ptr<uint16_t>(y0 + 1);
  return (1 - fy) * ((1 - fx) * r0[x0] + fx * r0[x0 + 1]) + fy * ((1 - fx) * r1[x0] + fx * r1[x0 + 1]);
}

// One ray's edge: the outermost fall through `level` within `reach` px of `c`, sub-pixel by
// linear interpolation between samples. false when the ray finds none.
bool RayEdge(const cv::Mat& image, cv::Point2d c, double angle, double level, double reach,
             double* radius) {
  const double dx = std::cos(angle), dy = std::sin(angle);
  bool found = false;
  double previous = Bilinear(image, c.x, c.y);
  for (double t = kRayStepPx; t <= reach; t += kRayStepPx) {
    const double v = Bilinear(image, c.x + t * dx, c.y + t * dy);
    if (previous >= level && v < level) {
      *radius = t - kRayStepPx * (level - v) / (previous - v);
      found = true;
    }
    previous = v;
  }
  return found;
}

// Radial residual of p against the ellipse e: |p - centre| less the ellipse's radius along it.
double RadialResidual(const cv::RotatedRect& e, cv::Point2d p) {
  const double a = 0.5 * e.size.width, b = 0.5 * e.size.height;
  const double t = e.angle * kPi / 180.0;
  const double x = p.x - e.center.x, y = p.y - e.center.y;
  const double u = std::cos(t) * x + std::sin(t) * y, v = -std::sin(t) * x + std::cos(t) * y;
  const double r = std::hypot(u, v);
  if (r <= 0.0 || a <= 0.0 || b <= 0.0) return r;
  const double cu = u / r, cv = v / r;
  return r - 1.0 / std::sqrt(cu * cu / (a * a) + cv * cv / (b * b));
}

// An ellipse through most of the points: started as the circle of the points' median distance
// from c, then fitted (cv::fitEllipse) to the points within a band of it, tightened over rounds.
bool RobustEllipse(const std::vector<cv::Point2d>& points, cv::Point2d c, double band_px,
                   cv::RotatedRect* ellipse) {
  std::vector<double> r;
  for (const cv::Point2d& p : points) r.push_back(std::hypot(p.x - c.x, p.y - c.y));
  std::nth_element(r.begin(), r.begin() + r.size() / 2, r.end());
  *ellipse = cv::RotatedRect(cv::Point2f(c), cv::Size2f(2 * r[r.size() / 2], 2 * r[r.size() / 2]),
                             0.0f);
  const double bands[4] = {2.5 * band_px, 1.5 * band_px, band_px, band_px};
  for (double band : bands) {
    std::vector<cv::Point2f> inliers;
    for (const cv::Point2d& p : points) {
      if (std::abs(RadialResidual(*ellipse, p)) < band) inliers.emplace_back(p);
    }
    if (inliers.size() < std::max<std::size_t>(6, points.size() / 2)) return false;
    *ellipse = cv::fitEllipse(inliers);
  }
  return true;
}

// The rays' edge points (departed[i] when ray i finds no edge).
std::vector<cv::Point2d> EdgePoints(const cv::Mat& image, cv::Point2d c, double level,
                                    double reach, int rays, std::vector<bool>* departed) {
  std::vector<cv::Point2d> points(static_cast<std::size_t>(rays));
  departed->assign(static_cast<std::size_t>(rays), false);
  for (int i = 0; i < rays; ++i) {
    const double angle = 2.0 * kPi * i / rays;
    double radius = 0.0;
    if (RayEdge(image, c, angle, level, reach, &radius)) {
      points[i] = c + radius * cv::Point2d(std::cos(angle), std::sin(angle));
    } else {
      (*departed)[i] = true;
    }
  }
  return points;
}

// The share of the rays in runs of at least `min_run` departed rays (the rays close a circle).
double DepartedFraction(const std::vector<bool>& departed, int min_run) {
  const int n = static_cast<int>(departed.size());
  int start = 0;
  while (start < n && departed[start]) ++start;
  if (start == n) return 1.0;
  int counted = 0, run = 0;
  for (int k = 1; k <= n; ++k) {
    const int i = (start + k) % n;
    if (departed[i]) {
      ++run;
    } else {
      if (run >= min_run) counted += run;
      run = 0;
    }
  }
  return static_cast<double>(counted) / n;
}

// Plateau: the 90th percentile of the component's gray levels.
double PlateauLevel(const cv::Mat& image, const Segments& segments, const Blob& b) {
  std::vector<uint16_t> values;
  for (int y = b.rect.y; y < b.rect.br().y; ++y) {
    for (int x = b.rect.x; x < b.rect.br().x; ++x) {
      if (segments.labels.at<int32_t>(y, x) == b.label) values.push_back(image.at<uint16_t>(y, x));
    }
  }
  const auto at = values.begin() + static_cast<long>(0.9 * (values.size() - 1));
  std::nth_element(values.begin(), at, values.end());
  return *at;
}

// Pixels of the IRED's component farther than `reach` outside the ellipse.
int PixelsBeyond(const Segments& segments, const Blob& b, const cv::RotatedRect& e,
                 double reach) {
  int count = 0;
  for (int y = b.rect.y; y < b.rect.br().y; ++y) {
    for (int x = b.rect.x; x < b.rect.br().x; ++x) {
      if (segments.labels.at<int32_t>(y, x) == b.label &&
          RadialResidual(e, cv::Point2d(x, y)) > reach) {
        ++count;
      }
    }
  }
  return count;
}

// Whether the IRED's component holds two sources: above `level`, a second piece of some size
// whose peak stays below 0.8 of the largest piece's (a dimmer blob merged at the segmentation's
// low threshold; a disc cut in two by a cable keeps its plateau in both pieces: occlusion).
bool HoldsADimmerSource(const cv::Mat& image, const Segments& segments, const Blob& b,
                        double level) {
  cv::Mat above, own, labels, stats, centroids;
  cv::compare(image(b.rect), cv::Scalar(level), above, cv::CMP_GT);
  cv::compare(segments.labels(b.rect), cv::Scalar(b.label), own, cv::CMP_EQ);
  above &= own;
  const int n = cv::connectedComponentsWithStats(above, labels, stats, centroids, 8, CV_32S);
  if (n < 3) return false;
  std::vector<std::pair<int, double>> pieces;  // area, peak
  for (int label = 1; label < n; ++label) {
    double peak = 0.0;
    cv::minMaxLoc(image(b.rect), nullptr, &peak, nullptr, nullptr, labels == label);
    pieces.emplace_back(stats.at<int>(label, cv::CC_STAT_AREA), peak);
  }
  std::sort(pieces.rbegin(), pieces.rend());
  for (std::size_t i = 1; i < pieces.size(); ++i) {
    if (pieces[i].first >= std::max(4.0, 0.05 * pieces[0].first) &&
        pieces[i].second < 0.8 * pieces[0].second) {
      return true;
    }
  }
  return false;
}

}  // namespace

void AssessShape(const cv::Mat& image, const Segments& segments, const NoiseModel& noise,
                 const SceneOptions& options, SceneReport* report) {
  const Blob& ired = segments.blobs[static_cast<std::size_t>(segments.ired)];
  if (std::sqrt(ired.area / kPi) < options.occlusion_min_radius_px) return;
  const double plateau = PlateauLevel(image, segments, ired);
  const double level = noise.background + 0.5 * (plateau - noise.background);
  if (HoldsADimmerSource(image, segments, ired,
                         noise.background + 0.35 * (plateau - noise.background))) {
    report->second_source = true;
    report->second_source_gap_px = 0.0;
  }
  const double reach = 0.5 * std::hypot(ired.rect.width, ired.rect.height) + 3.0;
  std::vector<bool> departed;
  const std::vector<cv::Point2d> points =
      EdgePoints(image, ired.centroid, level, reach, options.occlusion_rays, &departed);
  std::vector<cv::Point2d> found;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!departed[i]) found.push_back(points[i]);
  }
  cv::RotatedRect ellipse;
  const double band = options.occlusion_residual_px;
  if (found.size() < 6 || !RobustEllipse(found, ired.centroid, band, &ellipse)) {
    report->occluded = options.detect_occlusion;
    report->occluded_edge_fraction = 1.0;
    return;
  }
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!departed[i] && std::abs(RadialResidual(ellipse, points[i])) > band) departed[i] = true;
  }
  if (options.detect_occlusion) {
    report->occluded_edge_fraction = DepartedFraction(departed, options.occlusion_min_run);
    report->occluded = report->occluded_edge_fraction >= options.occluded_min_fraction;
  }
  if (PixelsBeyond(segments, ired, ellipse, options.merged_reach_px) >= 3) {
    report->second_source = true;
    report->second_source_gap_px = 0.0;
  }
}

}  // namespace irdist::scene
