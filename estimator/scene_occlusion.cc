// The scene pass's look at the IRED's shape: a second source merged into it, and occlusion
// (estimator/scene.h, part 3). The half-maximum edge is found along rays from the blob's centroid
// (sub-pixel, bilinear) and an ellipse is fitted to it robustly: a clean disc (tilted up to
// 30 deg: axis ratio 0.87) keeps its edge within a few 0.01 px of the ellipse, a cut one does not.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "base/pi.h"
#include "estimator/scene.h"
#include "estimator/scene_internal.h"

namespace irdist::scene {
namespace {

constexpr double kRayStepPx = 0.5;  // an edge spans 2 px and more: linear between samples

double Bilinear(const cv::Mat& image, double x, double y) {
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  if (x0 < 0 || y0 < 0 || x0 + 1 >= image.cols || y0 + 1 >= image.rows) return 0.0;
  const double fx = x - x0, fy = y - y0;
  const uint16_t* r0 = image.ptr<uint16_t>(y0);
  const uint16_t* r1 = image.ptr<uint16_t>(y0 + 1);
  return (1 - fy) * ((1 - fx) * r0[x0] + fx * r0[x0 + 1]) + fy * ((1 - fx) * r1[x0] + fx * r1[x0 + 1]);
}

// One ray's edge: the outermost fall through `level` among the samples at start + k kRayStepPx
// (k = 0, 1, ... up to `reach`) px from `c`, sub-pixel by linear interpolation between samples.
// Scanned inward from the outermost sample, it stops at the first fall it meets: beyond a disc's
// edge a few samples, not the whole ray. false when the ray finds none.
bool RayEdge(const cv::Mat& image, cv::Point2d c, double angle, double level, double start,
             double reach, double* radius) {
  const double dx = std::cos(angle), dy = std::sin(angle);
  const auto sample = [&](int k) {
    const double t = start + kRayStepPx * k;
    return Bilinear(image, c.x + t * dx, c.y + t * dy);
  };
  int k = static_cast<int>(std::floor((reach - start) / kRayStepPx));
  if (k < 1) return false;
  double outer = sample(k);
  for (; k >= 1; --k) {
    const double inner = sample(k - 1);
    if (inner >= level && outer < level) {
      *radius = start + kRayStepPx * k - kRayStepPx * (level - outer) / (inner - outer);
      return true;
    }
    outer = inner;
  }
  return false;
}

// An ellipse (cv::RotatedRect) ready for radial residuals: |p - centre| less the ellipse's
// radius along p - centre.
class RadialEllipse {
 public:
  explicit RadialEllipse(const cv::RotatedRect& e)
      : cx_(e.center.x), cy_(e.center.y), c_(std::cos(e.angle * kPi / 180.0)),
        s_(std::sin(e.angle * kPi / 180.0)), ia2_(4.0 / (e.size.width * e.size.width)),
        ib2_(4.0 / (e.size.height * e.size.height)) {}
  double Residual(cv::Point2d p) const {
    const double x = p.x - cx_, y = p.y - cy_;
    const double u = c_ * x + s_ * y, v = -s_ * x + c_ * y;
    const double r2 = u * u + v * v;
    if (!(r2 > 0.0) || !std::isfinite(ia2_ + ib2_)) return std::sqrt(r2);
    return std::sqrt(r2) * (1.0 - 1.0 / std::sqrt(u * u * ia2_ + v * v * ib2_));
  }

 private:
  double cx_, cy_, c_, s_, ia2_, ib2_;
};


// The least-squares conic A u^2 + B uv + C v^2 + D u + E v = 1 through the points (u, v taken
// from their mean, for conditioning) as an ellipse; false when the conic is not one. A 5 x 5
// solve: the rays' points are dense and nearly round, where the plain algebraic fit is sound.
bool FitConicEllipse(const std::vector<cv::Point2d>& points, cv::RotatedRect* ellipse) {
  if (points.size() < 6) return false;
  cv::Point2d mean(0.0, 0.0);
  for (const cv::Point2d& p : points) mean += p;
  mean *= 1.0 / points.size();
  cv::Matx<double, 5, 5> ata = cv::Matx<double, 5, 5>::zeros();
  cv::Matx<double, 5, 1> atb = cv::Matx<double, 5, 1>::zeros();
  for (const cv::Point2d& p : points) {
    const double u = p.x - mean.x, v = p.y - mean.y;
    const cv::Matx<double, 5, 1> row(u * u, u * v, v * v, u, v);
    ata += row * row.t();
    atb += row;
  }
  cv::Matx<double, 5, 1> k;
  if (!cv::solve(ata, atb, k, cv::DECOMP_CHOLESKY)) return false;
  const double a = k(0), b = 0.5 * k(1), c = k(2);
  const double det = a * c - b * b;
  if (!(det > 0.0)) return false;
  // Centre: the gradient's zero; the constant there, -1 + (D u0 + E v0) / 2.
  const double u0 = (-k(3) * c + k(4) * b) / (2.0 * det), v0 = (-k(4) * a + k(3) * b) / (2.0 * det);
  const double f0 = -1.0 + 0.5 * (k(3) * u0 + k(4) * v0);
  const double mid = 0.5 * (a + c), root = std::sqrt(0.25 * (a - c) * (a - c) + b * b);
  const double l1 = mid - root, l2 = mid + root;  // l1 <= l2: the major axis along l1
  if (!(l1 > 0.0) || !(f0 < 0.0)) return false;
  const double angle = 0.5 * std::atan2(2.0 * b, a - c) + 0.5 * kPi;  // l1's direction
  *ellipse = cv::RotatedRect(cv::Point2f(static_cast<float>(mean.x + u0), static_cast<float>(mean.y + v0)),
                             cv::Size2f(static_cast<float>(2.0 * std::sqrt(-f0 / l1)),
                                        static_cast<float>(2.0 * std::sqrt(-f0 / l2))),
                             static_cast<float>(angle * 180.0 / kPi));
  return true;
}

// An ellipse through most of the points: started as the circle of the points' median distance
// from c, then fitted (FitConicEllipse) to the points within a band of it, tightened over rounds.
bool RobustEllipse(const std::vector<cv::Point2d>& points, cv::Point2d c, double band_px,
                   cv::RotatedRect* ellipse) {
  std::vector<double> r;
  for (const cv::Point2d& p : points) r.push_back(std::hypot(p.x - c.x, p.y - c.y));
  std::nth_element(r.begin(), r.begin() + r.size() / 2, r.end());
  *ellipse = cv::RotatedRect(cv::Point2f(c), cv::Size2f(2 * r[r.size() / 2], 2 * r[r.size() / 2]),
                             0.0f);
  const double bands[4] = {2.5 * band_px, 1.5 * band_px, band_px, band_px};
  for (double band : bands) {
    const RadialEllipse e(*ellipse);
    std::vector<cv::Point2d> inliers;
    for (const cv::Point2d& p : points) {
      if (std::abs(e.Residual(p)) < band) inliers.push_back(p);
    }
    if (inliers.size() < std::max<std::size_t>(6, points.size() / 2) ||
        !FitConicEllipse(inliers, ellipse)) {
      return false;
    }
  }
  return true;
}

// The rays' edge points (departed[i] when ray i finds no edge).
std::vector<cv::Point2d> EdgePoints(const cv::Mat& image, cv::Point2d c, double level,
                                    double start, double reach, int rays,
                                    std::vector<bool>* departed) {
  std::vector<cv::Point2d> points(static_cast<std::size_t>(rays));
  departed->assign(static_cast<std::size_t>(rays), false);
  for (int i = 0; i < rays; ++i) {
    const double angle = 2.0 * kPi * i / rays;
    double radius = 0.0;
    if (RayEdge(image, c, angle, level, start, reach, &radius)) {
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
int PixelsBeyond(const Segments& segments, const Blob& b, const cv::RotatedRect& ellipse,
                 double reach) {
  const RadialEllipse e(ellipse);
  int count = 0;
  for (int y = b.rect.y; y < b.rect.br().y; ++y) {
    for (int x = b.rect.x; x < b.rect.br().x; ++x) {
      if (segments.labels.at<int32_t>(y, x) == b.label &&
          e.Residual(cv::Point2d(x, y)) > reach) {
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
  std::vector<std::pair<int, double>> pieces(static_cast<std::size_t>(n));  // area, peak
  for (int y = 0; y < labels.rows; ++y) {
    const int32_t* label = labels.ptr<int32_t>(y);
    const uint16_t* row = image.ptr<uint16_t>(b.rect.y + y) + b.rect.x;
    for (int x = 0; x < labels.cols; ++x) {
      double& peak = pieces[static_cast<std::size_t>(label[x])].second;
      peak = std::max<double>(peak, row[x]);
    }
  }
  for (int label = 1; label < n; ++label) pieces[label].first = stats.at<int>(label, cv::CC_STAT_AREA);
  pieces.erase(pieces.begin());  // the background
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
  const double reach = 0.5 * std::max(ired.rect.width, ired.rect.height) + 3.0;
  std::vector<bool> departed;
  // The rays start well inside the disc (a quarter of its box's smaller side from the centroid).
  const double start = 0.25 * std::min(ired.rect.width, ired.rect.height);
  const std::vector<cv::Point2d> points =
      EdgePoints(image, ired.centroid, level, start, reach, options.occlusion_rays, &departed);
  std::vector<cv::Point2d> found;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!departed[i]) found.push_back(points[i]);
  }
  cv::RotatedRect ellipse;
  const double band = options.occlusion_residual_px;
  const bool shaped = found.size() >= 6 && RobustEllipse(found, ired.centroid, band, &ellipse);
  double fraction = 1.0;  // no ellipse: the whole edge is in doubt
  if (shaped) {
    const RadialEllipse fitted(ellipse);
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (!departed[i] && std::abs(fitted.Residual(points[i])) > band) departed[i] = true;
    }
    fraction = DepartedFraction(departed, options.occlusion_min_run);
  }
  if (options.detect_occlusion) {
    report->occluded_edge_fraction = fraction;
    report->occluded = fraction >= options.occluded_min_fraction;
  }
  // A dimmer source merged with the disc: its pixels beyond the ellipse, or (where the edge is in
  // doubt) a dimmer piece of the component.
  const bool merged =
      (shaped && PixelsBeyond(segments, ired, ellipse, options.merged_reach_px) >= 3) ||
      (fraction >= options.occluded_min_fraction &&
       HoldsADimmerSource(image, segments, ired,
                          noise.background + 0.35 * (plateau - noise.background)));
  if (merged) {
    report->second_source = true;
    report->second_source_gap_px = 0.0;
  }
}

}  // namespace irdist::scene
