#include "estimator/features.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <cstdint>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <vector>

#include "base/check.h"
#include "base/pi.h"
#include "estimator/disc_fit.h"
#include "estimator/gray_histogram.h"
#include "estimator/window_scan.h"

namespace irdist {
namespace {

// The moments' threshold is at least this many noise sd above the background: a noise pixel
// passes 5 sd in 3e-7 of draws, once in about 800 windows of 64 x 64.
constexpr double kMomentNoiseSigmas = 5.0;
// A normal distribution's sd over its median absolute deviation.
constexpr double kMadToSd = 1.4826;

// Median and median absolute deviation of a strided subsample of a CV_16UC1 image.
void RobustBackground(const cv::Mat& coarse, double* median, double* mad) {
  std::vector<uint16_t> values;
  values.reserve(coarse.total() / 3 + 1);
  for (int y = 0; y < coarse.rows; ++y) {
    const uint16_t* row = coarse.ptr<uint16_t>(y);
    for (int x = (y % 3); x < coarse.cols; x += 3) values.push_back(row[x]);
  }
  IRDIST_CHECK(!values.empty(), "empty image");
  const GrayHistogram levels(values);
  *median = levels.Median();
  *mad = levels.MedianAbsoluteDeviation();
}

cv::Rect SquareAround(double cx, double cy, int side) {
  const int x0 = static_cast<int>(std::lround(cx - 0.5 * (side - 1)));
  const int y0 = static_cast<int>(std::lround(cy - 0.5 * (side - 1)));
  return cv::Rect(x0, y0, side, side);
}

// Background-subtracted first and second moments of the pixels above `threshold` in `rect`.
struct Moments {
  double weight = 0.0, cx = 0.0, cy = 0.0, sxx = 0.0, syy = 0.0, sxy = 0.0;
  double radius = 0.0, background = 0.0;  // kAperture: the aperture and its background
};

// The weighted sums of the moments, of coordinates as given (absolute, or from a centre).
struct MomentSums {
  double w = 0.0, sx = 0.0, sy = 0.0, sxx = 0.0, syy = 0.0, sxy = 0.0;
  void Add(double weight, double x, double y) {
    w += weight;
    sx += weight * x;
    sy += weight * y;
    sxx += weight * x * x;
    syy += weight * y * y;
    sxy += weight * x * y;
  }
  // The weight, and the central second moments into *m with the mean in (*mx, *my); false (the
  // weight alone set) when the weight is not positive.
  bool Central(Moments* m, double* mx, double* my) const {
    m->weight = w;
    if (w <= 0.0) return false;
    *mx = sx / w;
    *my = sy / w;
    m->sxx = sxx / w - *mx * *mx;
    m->syy = syy / w - *my * *my;
    m->sxy = sxy / w - *mx * *my;
    return true;
  }
};

Moments WeightedMoments(const cv::Mat& image, const cv::Rect& rect, double background,
                        double threshold) {
  MomentSums sums;
  const LevelAbove above(threshold);
  for (int y = rect.y; y < rect.y + rect.height; ++y) {
    const uint16_t* row = image.ptr<uint16_t>(y);
    if (!above.AnyIn(row + rect.x, rect.width)) continue;
    for (int x = rect.x; x < rect.x + rect.width; ++x) {
      if (above(row[x])) sums.Add(row[x] - background, x, y);
    }
  }
  Moments m;
  sums.Central(&m, &m.cx, &m.cy);
  return m;
}

// kAperture: moments of every pixel within `radius` of (cx, cy), background-subtracted with the
// mean of the window's pixels beyond radius + 1 (the blob's support ends well inside the radius).
Moments ApertureMoments(const cv::Mat& image, const cv::Rect& rect, double cx, double cy,
                        double radius, double fallback_background) {
  std::int64_t outside = 0;
  int n_outside = 0;
  const double r_in2 = radius * radius, r_out2 = (radius + 1.0) * (radius + 1.0);
  const int end = rect.x + rect.width;
  for (int y = rect.y; y < rect.y + rect.height; ++y) {
    const uint16_t* row = image.ptr<uint16_t>(y);
    const ColumnRun in = ColumnsWithin(y, cx, cy, r_out2, rect.x, end);
    outside += SumLevels(row, rect.x, in.first) + SumLevels(row, in.last, end);
    n_outside += (in.first - rect.x) + (end - in.last);
  }
  const double background =
      n_outside >= 64 ? static_cast<double>(outside) / n_outside : fallback_background;
  MomentSums sums;
  for (int y = rect.y; y < rect.y + rect.height; ++y) {
    const uint16_t* row = image.ptr<uint16_t>(y);
    const double dy = y - cy;
    const ColumnRun in = ColumnsWithin(y, cx, cy, r_in2, rect.x, end);
    for (int x = in.first; x < in.last; ++x) sums.Add(row[x] - background, x - cx, dy);
  }
  Moments m;
  double mx = 0.0, my = 0.0;
  if (!sums.Central(&m, &mx, &my)) return m;
  m.radius = radius;
  m.background = background;
  m.cx = cx + mx;
  m.cy = cy + my;
  return m;
}

// The blur variance (px^2, per axis) from the 2nd and 4th cumulants of the aperture's intensity
// along the blob's two principal axes. A uniformly bright disc (or its tilted image, an ellipse)
// projects onto an axis as a semicircle law of cumulants k2 = a^2/4, k4 = -a^4/16 (a the semi-axis);
// a Gaussian blur adds s^2 to k2 and nothing to k4 (the pixel's box adds 1/12 and -1/120). So
// k2 - sqrt(-k4) = s^2 + 1/12 along either axis, whatever d and theta: a blur measured on the frame
// itself. The mean of the two axes; NaN when the aperture or the cumulants do not allow it.
double ApertureBlurVariance(const cv::Mat& image, const cv::Rect& rect, const Moments& m) {
  if (!(m.radius > 0.0) || !(m.weight > 0.0)) return std::numeric_limits<double>::quiet_NaN();
  const double angle = 0.5 * std::atan2(2.0 * m.sxy, m.sxx - m.syy);
  const double c = std::cos(angle), s = std::sin(angle);
  double w = 0.0, p2 = 0.0, p4 = 0.0, q2 = 0.0, q4 = 0.0;
  const double r2 = m.radius * m.radius;
  for (int y = rect.y; y < rect.y + rect.height; ++y) {
    const uint16_t* row = image.ptr<uint16_t>(y);
    const double dy = y - m.cy;
    const ColumnRun in = ColumnsWithin(y, m.cx, m.cy, r2, rect.x, rect.x + rect.width);
    for (int x = in.first; x < in.last; ++x) {
      const double dx = x - m.cx;
      const double g = row[x] - m.background;
      const double p = c * dx + s * dy, q = -s * dx + c * dy;
      w += g;
      p2 += g * p * p;
      p4 += g * p * p * p * p;
      q2 += g * q * q;
      q4 += g * q * q * q * q;
    }
  }
  if (!(w > 0.0)) return std::numeric_limits<double>::quiet_NaN();
  auto blur = [w](double m2, double m4) {
    const double k2 = m2 / w, k4 = m4 / w - 3.0 * (m2 / w) * (m2 / w);
    return k4 < 0.0 ? k2 - std::sqrt(-k4) : std::numeric_limits<double>::quiet_NaN();
  };
  return 0.5 * (blur(p2, p4) + blur(q2, q4));
}

// Pixels at the format's maximum inside `roi` of the raw frame.
int CountSaturated(const cv::Mat& image, const cv::Rect& roi, int bit_depth) {
  const int saturated_level = (1 << bit_depth) - 1;
  int saturated = 0;
  const cv::Rect clipped = roi & cv::Rect(0, 0, image.cols, image.rows);
  for (int y = clipped.y; y < clipped.y + clipped.height; ++y) {
    const std::uint16_t* row = image.ptr<std::uint16_t>(y);
    for (int x = clipped.x; x < clipped.x + clipped.width; ++x) saturated += row[x] >= saturated_level;
  }
  return saturated;
}

// ResponseScope::kAllPixels: the features of the linearised frame, with the raw frame's saturation.
Features FeaturesOfLinearisedFrame(const cv::Mat& image, int bit_depth,
                                   const FeatureOptions& options) {
  FeatureOptions linear_options = options;
  linear_options.inverse_response = InverseResponse();
  linear_options.response_scope = ResponseScope::kERelOnly;
  Features out = ComputeFeatures(LineariseFrame(image, bit_depth, options.inverse_response), 16,
                                 linear_options);
  out.bit_depth = bit_depth;
  // Saturation is a property of the raw frame: pixels at the format's maximum in the ROI (the
  // threshold ROI's brightest pixels always lie inside its bounding box).
  if (out.blob_found) out.saturated_pixels = CountSaturated(image, out.roi, bit_depth);
  return out;
}

// Where the blob is: the robust background, the peak and the intensity centroid.
struct BlobLocation {
  double background = 0.0;  // gray levels
  double peak = 0.0;        // gray levels
  double cx = 0.0, cy = 0.0;
};

}  // namespace

// The mean of each k x k block of a CV_16UC1 image, rounded as cv::resize's INTER_AREA rounds
// (k = 2: half up; else to nearest even in float): its result, about 4x faster (its generic path
// was a quarter of the full frame's features; tests/estimator/features_test.cc compares the
// two). Rows summed first into 32-bit columns, then each block's k columns. An image whose sides
// are not multiples of k goes to cv::resize.
cv::Mat DownsampleArea(const cv::Mat& image, int k) {
  IRDIST_CHECK(k >= 1, "downsampling factor " + std::to_string(k) + " below 1");
  const int rows = image.rows / k, cols = image.cols / k;
  cv::Mat out;
  if (image.type() != CV_16UC1 || rows * k != image.rows || cols * k != image.cols) {
    cv::resize(image, out, cv::Size(cols, rows), 0, 0, cv::INTER_AREA);
    return out;
  }
  out.create(rows, cols, CV_16UC1);
  std::vector<std::uint32_t> columns(image.cols);
  const float scale = 1.0f / static_cast<float>(k * k);
  for (int r = 0; r < rows; ++r) {
    const std::uint16_t* first = image.ptr<std::uint16_t>(r * k);
    for (int x = 0; x < image.cols; ++x) columns[x] = first[x];
    for (int i = 1; i < k; ++i) {
      const std::uint16_t* in = image.ptr<std::uint16_t>(r * k + i);
      for (int x = 0; x < image.cols; ++x) columns[x] += in[x];
    }
    std::uint16_t* o = out.ptr<std::uint16_t>(r);
    for (int c = 0; c < cols; ++c) {
      std::uint32_t sum = 0;
      for (int j = 0; j < k; ++j) sum += columns[c * k + j];
      o[c] = k == 2 ? static_cast<std::uint16_t>((sum + 2) >> 2)
                    : cv::saturate_cast<std::uint16_t>(static_cast<float>(sum) * scale);
    }
  }
  return out;
}

namespace {

// Coarse pass: area-average downsampling, robust background, brightest coarse cell. Returns false
// when its contrast is below the options' minimum (no blob); sets the background and the coarse
// peak's position (full-resolution pixels) either way.
bool DetectCoarse(const cv::Mat& image, double max_gray, const FeatureOptions& options,
                  BlobLocation* at) {
  const int k = options.detection_downsample;
  cv::Mat coarse;
  if (k > 1) {
    coarse = DownsampleArea(image, k);
  } else {
    coarse = image;
  }
  double mad = 0.0;
  RobustBackground(coarse, &at->background, &mad);
  double coarse_peak = 0.0;
  cv::Point coarse_at;
  cv::minMaxLoc(coarse, nullptr, &coarse_peak, nullptr, &coarse_at);
  const double min_contrast =
      std::max(options.min_contrast_fraction * max_gray, 8.0 * kMadToSd * mad);
  at->cx = coarse_at.x * k + 0.5 * (k - 1);
  at->cy = coarse_at.y * k + 0.5 * (k - 1);
  return coarse_peak - at->background >= min_contrast;
}

// Full resolution, in a window around the coarse peak: peak and intensity centroid (up to four
// re-centred passes). Returns false when no pixel is above the moment threshold.
bool LocateCentroid(const cv::Mat& image, const FeatureOptions& options, BlobLocation* at) {
  const cv::Rect frame(0, 0, image.cols, image.rows);
  for (int iteration = 0; iteration < 4; ++iteration) {
    const cv::Rect window = SquareAround(at->cx, at->cy, options.window_side_px) & frame;
    cv::minMaxLoc(image(window), nullptr, &at->peak, nullptr, nullptr);
    const double threshold =
        at->background + options.moment_threshold_fraction * (at->peak - at->background);
    const Moments m = WeightedMoments(image, window, at->background, threshold);
    if (m.weight <= 0.0) return false;
    const double shift = std::hypot(m.cx - at->cx, m.cy - at->cy);
    at->cx = m.cx;
    at->cy = m.cy;
    if (shift < 0.25) break;
  }
  return true;
}

// Border flags: a clipped window, or blob pixels on the outermost image rows/columns, or on the
// edge of the fixed window. Only the window's outermost pixels can be either (the window lies in
// the image).
void FlagBorders(const cv::Mat& image, const cv::Rect& window, const cv::Rect& full_window,
                 double roi_threshold, const FeatureOptions& options, Features* out) {
  out->touches_border = window != full_window;
  const LevelAbove above(roi_threshold);
  const bool fixed = options.roi_policy == RoiPolicy::kFixedWindow;
  const auto check = [&](int x, int y) {
    if (!above(image.at<uint16_t>(y, x))) return;
    if (x == 0 || y == 0 || x == image.cols - 1 || y == image.rows - 1) out->touches_border = true;
    if (fixed) out->blob_clipped_by_roi = true;  // on the window's edge
  };
  const int right = window.x + window.width - 1, bottom = window.y + window.height - 1;
  for (int x = window.x; x <= right; ++x) {
    check(x, window.y);
    check(x, bottom);
  }
  for (int y = window.y + 1; y < bottom; ++y) {
    check(window.x, y);
    check(right, y);
  }
}

// The gray levels of the window's border ring, kBorderPx wide (away from the blob).
constexpr int kBorderPx = 4;
std::vector<uint16_t> BorderRing(const cv::Mat& image, const cv::Rect& window) {
  std::vector<uint16_t> border;
  for (int y = window.y; y < window.y + window.height; ++y) {
    const uint16_t* row = image.ptr<uint16_t>(y);
    const bool edge_row = y < window.y + kBorderPx || y >= window.y + window.height - kBorderPx;
    for (int x = window.x; x < window.x + window.width; ++x) {
      if (edge_row || x < window.x + kBorderPx || x >= window.x + window.width - kBorderPx) {
        border.push_back(row[x]);
      }
    }
  }
  return border;
}

// How far the blob's light reaches beyond its farthest pixel above the ROI threshold (px): the
// blur's tail, a few sigma.
constexpr double kBackgroundMarginPx = 4.0;

// The window's background (gray levels): the mean of the pixels of a square four times the
// window's side around the blob (the whole 256 px ROI at the default 64 px window), beyond the
// blob's reach (the farthest pixel of the window above `threshold` from (cx, cy), plus
// kBackgroundMarginPx), within 5 robust sd of their median (a stray bright pixel does not move
// it). The square is centred on the blob, so a smooth gradient's mean over it is its value under
// the blob: the window's sum loses exactly the background there. Its area keeps the mean's noise,
// times the window's area in F(0,0), below the signal's: the Fig. 14 pose's d scatter is 1.12 mm
// as without subtraction (1.24 from the window's border alone, 1.14 from a square of twice its
// side, whose noise also raised the motion check's false alarms).
double WindowBackground(const cv::Mat& image, const cv::Rect& window, double threshold,
                        double max_gray, double cx, double cy) {
  const double reach = std::sqrt(FarthestAbove2(image, window, threshold, cx, cy)) +
                       kBackgroundMarginPx;
  const cv::Rect around =
      SquareAround(cx, cy, 4 * window.width) & cv::Rect(0, 0, image.cols, image.rows);
  GrayHistogram levels(static_cast<int>(max_gray));
  const double reach2 = reach * reach;
  const int end = around.x + around.width;
  for (int y = around.y; y < around.y + around.height; ++y) {
    const uint16_t* row = image.ptr<uint16_t>(y);
    const ColumnRun blob = ColumnsWithin(y, cx, cy, reach2, around.x, end);
    levels.AddRun(row + around.x, blob.first - around.x);
    levels.AddRun(row + blob.last, end - blob.last);
  }
  if (levels.size() < 32) levels = GrayHistogram(BorderRing(image, window));
  const double median = levels.Median();
  const double limit = 5.0 * std::max(kMadToSd * levels.MedianAbsoluteDeviation(), 1.0);
  int n = 0;
  return levels.ClippedMean(median, limit, &n);
}

// ROI statistics: E_rel, F(0,0), Sigma, saturation, the ROI itself. Returns false when the ROI is
// empty.
bool RoiStatistics(const cv::Mat& image, const cv::Rect& window, double roi_threshold,
                   double max_gray, const cv::Point2d& centre, const FeatureOptions& options,
                   Features* out) {
  const bool fixed = options.roi_policy == RoiPolicy::kFixedWindow;
  const InverseResponse& f = options.inverse_response;
  const uint16_t saturated_level = static_cast<uint16_t>(max_gray);
  const LevelAbove above(roi_threshold);
  const bool identity = f.IsIdentity();
  double sum = 0.0, sum_sq = 0.0, sum_f = 0.0;
  int area = 0, saturated = 0;
  int min_x = image.cols, min_y = image.rows, max_x = -1, max_y = -1;
  for (int y = window.y; y < window.y + window.height; ++y) {
    const uint16_t* row = image.ptr<uint16_t>(y);
    for (int x = window.x; x < window.x + window.width; ++x) {
      if (!fixed && !above(row[x])) continue;
      const double mv = row[x] / max_gray;
      sum += mv;
      sum_sq += mv * mv;
      sum_f += identity ? mv : f.Apply(mv);
      ++area;
      if (row[x] >= saturated_level) ++saturated;
      if (fixed) continue;  // the window is the ROI
      min_x = std::min(min_x, x);
      max_x = std::max(max_x, x);
      min_y = std::min(min_y, y);
      max_y = std::max(max_y, y);
    }
  }
  if (area == 0) return false;
  out->roi = fixed ? window : cv::Rect(min_x, min_y, max_x - min_x + 1, max_y - min_y + 1);
  out->roi_area_px = area;
  out->saturated_pixels = saturated;
  // Measured only where it is taken off (the paper's features and older models skip the scan).
  if (options.subtract_background) {
    out->window_background =
        WindowBackground(image, window, roi_threshold, max_gray, centre.x, centre.y) / max_gray;
  }
  const double bg = out->window_background;
  const double bg_f = options.subtract_background && !f.IsIdentity() ? f.Apply(bg) : bg;
  out->f00 = sum - area * bg;
  out->e_rel = sum_f / area - bg_f;
  const double mean = sum / area;
  out->sigma = std::sqrt(std::max(0.0, sum_sq / area - mean * mean));
  return true;
}

// Background-subtracted second moments of the window (MomentMethod::kAperture: inside an aperture
// reaching the thresholded support plus a margin, which also measures the blur).
Moments BlobMoments(const cv::Mat& image, const cv::Rect& window, double background,
                    double moment_threshold, const FeatureOptions& options, Features* out) {
  const Moments m = WeightedMoments(image, window, background, moment_threshold);
  if (options.moment_method != MomentMethod::kAperture || !(m.weight > 0.0)) return m;
  // Support: the farthest pixel above the moment threshold from the thresholded centroid.
  const double support2 = FarthestAbove2(image, window, moment_threshold, m.cx, m.cy);
  const Moments a = ApertureMoments(image, window, m.cx, m.cy,
                                    std::sqrt(support2) + options.aperture_margin_px, background);
  if (!(a.weight > 0.0 && a.sxx > 0.0 && a.syy > 0.0)) return m;
  out->blur_var_px2 = ApertureBlurVariance(image, window, a);
  return a;
}

// The moments' principal variances, and the ellipse they give with the PSF blur removed.
void MomentEllipse(const Moments& m, const FeatureOptions& options, Features* out) {
  const double tr = m.sxx + m.syy;
  const double det_root =
      std::sqrt(std::max(0.0, 0.25 * (m.sxx - m.syy) * (m.sxx - m.syy) + m.sxy * m.sxy));
  const double l1 = 0.5 * tr + det_root;
  const double l2 = 0.5 * tr - det_root;
  out->moment_major_var_px2 = l1;
  out->moment_minor_var_px2 = l2;
  const double blur2 = options.psf_sigma_px * options.psf_sigma_px;
  EllipseFit& e = out->ellipse_moments;
  if (!(l1 - blur2 > 0.0)) return;
  e.valid = true;
  e.center_px = cv::Point2d(m.cx, m.cy);
  // A uniform ellipse of semi-axis a has variance a^2/4 along it: full axis = 4 sqrt(var).
  e.major_px = 4.0 * std::sqrt(l1 - blur2);
  e.minor_px = 4.0 * std::sqrt(std::max(0.0, l2 - blur2));
  e.angle_deg = 0.5 * std::atan2(2.0 * m.sxy, m.sxx - m.syy) * 180.0 / kPi;
  e.theta0_deg = Theta0FromAxes(e.minor_px, e.major_px);
}

// Ellipse fitted (cv::fitEllipse) to the largest contour above `half_threshold` in the window.
EllipseFit ContourEllipse(const cv::Mat& image, const cv::Rect& window, double half_threshold) {
  EllipseFit e;
  cv::Mat mask;
  cv::compare(image(window), cv::Scalar(half_threshold), mask, cv::CMP_GT);
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(mask, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
  size_t best = contours.size();
  double best_area = -1.0;
  for (size_t i = 0; i < contours.size(); ++i) {
    const double a = cv::contourArea(contours[i]);
    if (a > best_area) {
      best_area = a;
      best = i;
    }
  }
  if (best == contours.size() || contours[best].size() < 5) return e;
  const cv::RotatedRect r = cv::fitEllipse(contours[best]);
  e.valid = true;
  e.center_px = cv::Point2d(r.center.x + window.x, r.center.y + window.y);
  e.major_px = std::max(r.size.width, r.size.height);
  e.minor_px = std::min(r.size.width, r.size.height);
  e.angle_deg = r.size.width >= r.size.height ? r.angle : r.angle + 90.0;
  e.theta0_deg = Theta0FromAxes(e.minor_px, e.major_px);
  return e;
}

// Ellipse from the blurred, pixel-integrated disc model (kModelFit), started from the moments; the
// fitted box reaches the farthest pixel above half maximum (far above the noise) from the centroid
// plus the blur's reach.
void ModelFitEllipse(const cv::Mat& image, const cv::Rect& window, double max_gray,
                     const Moments& m, const BlobLocation& at, double half_threshold,
                     const FeatureOptions& options, Features* out) {
  const double s0 = options.psf_sigma_px > 0.0 ? options.psf_sigma_px : 0.7;
  const double half_max2 = FarthestAbove2(image, window, half_threshold, m.cx, m.cy);
  const double half = std::sqrt(half_max2) + 4.0 * s0 + 1.5;
  const int x0 = static_cast<int>(std::floor(m.cx - half));
  const int y0 = static_cast<int>(std::floor(m.cy - half));
  const int x1 = static_cast<int>(std::ceil(m.cx + half));
  const int y1 = static_cast<int>(std::ceil(m.cy + half));
  const cv::Rect box = cv::Rect(x0, y0, x1 - x0 + 1, y1 - y0 + 1) & window;
  FitDisc(image, box, max_gray, DiscMoments{m.cx, m.cy, m.sxx, m.syy, m.sxy},
          out->ellipse_contour, at.background, at.peak, s0,
          &out->ellipse_model, &out->model_blur_px, &out->model_rms);
}

const EllipseFit& ChosenEllipse(const Features& f, EllipseMethod method) {
  switch (method) {
    case EllipseMethod::kMoments:
      return f.ellipse_moments;
    case EllipseMethod::kContour:
      return f.ellipse_contour;
    case EllipseMethod::kModelFit:
      break;
  }
  return f.ellipse_model.valid ? f.ellipse_model : f.ellipse_moments;
}

// The read noise's sd (gray levels) on the window's border (a 4 px frame, away from the blob):
// RobustNoiseSd. 0 when the border is too small to say.
double BorderNoiseSd(const cv::Mat& image, const cv::Rect& window) {
  const GrayHistogram border(BorderRing(image, window));
  return border.size() < 32 ? 0.0 : kMadToSd * border.MedianAbsoluteDeviation();
}

// Steps 3-7 of ComputeFeatures on a located blob: borders, ROI statistics, the three ellipses.
void MeasureBlob(const cv::Mat& image, double max_gray, const BlobLocation& at,
                 const FeatureOptions& options, Features* out) {
  const cv::Rect full_window = SquareAround(at.cx, at.cy, options.window_side_px);
  const cv::Rect window = full_window & cv::Rect(0, 0, image.cols, image.rows);
  const double contrast = at.peak - at.background;
  // The moments' threshold stays kMomentNoiseSigmas above the noise: on a dim frame 2% of the
  // contrast is within the noise, and one noise pixel far out set the aperture's support.
  const double moment_threshold =
      at.background + std::max(options.moment_threshold_fraction * contrast,
                               kMomentNoiseSigmas * BorderNoiseSd(image, window));
  const double roi_threshold = at.background + options.threshold_fraction * contrast;
  const double half_threshold = at.background + 0.5 * contrast;
  FlagBorders(image, window, full_window, roi_threshold, options, out);
  if (!RoiStatistics(image, window, roi_threshold, max_gray, cv::Point2d(at.cx, at.cy), options,
                     out)) {
    out->blob_found = false;
    return;
  }
  const Moments m = BlobMoments(image, window, at.background, moment_threshold, options, out);
  MomentEllipse(m, options, out);
  out->ellipse_contour = ContourEllipse(image, window, half_threshold);
  if (options.ellipse_method == EllipseMethod::kModelFit && m.weight > 0.0 &&
      out->moment_major_var_px2 > 0.0) {
    ModelFitEllipse(image, window, max_gray, m, at, half_threshold, options, out);
  }
  out->theta0_deg = ChosenEllipse(*out, options.ellipse_method).theta0_deg;
}

}  // namespace

Features ComputeFeatures(const cv::Mat& image, int bit_depth, const FeatureOptions& options) {
  std::string why;
  IRDIST_CHECK(options.IsValid(&why), why);
  IRDIST_CHECK(image.type() == CV_16UC1, "ComputeFeatures needs a CV_16UC1 image, got type ",
               image.type());
  IRDIST_CHECK(bit_depth >= 8 && bit_depth <= 16, "bit_depth must be in [8,16], got ", bit_depth);
  if (options.response_scope == ResponseScope::kAllPixels &&
      !options.inverse_response.IsIdentity()) {
    return FeaturesOfLinearisedFrame(image, bit_depth, options);
  }
  IRDIST_CHECK(image.rows >= options.window_side_px && image.cols >= options.window_side_px,
               "image smaller than the ROI window");
  Features out;
  out.bit_depth = bit_depth;
  const double max_gray = static_cast<double>((1 << bit_depth) - 1);
  // 1. Coarse detection; 2. the centroid at full resolution.
  BlobLocation at;
  const bool detected = DetectCoarse(image, max_gray, options, &at);
  out.background = at.background / max_gray;
  if (!detected || !LocateCentroid(image, options, &at)) return out;  // no blob
  out.blob_found = true;
  out.peak = at.peak / max_gray;
  out.centroid_px = cv::Point2d(at.cx, at.cy);
  // 3-7. Borders, ROI statistics, ellipses, theta0.
  MeasureBlob(image, max_gray, at, options, &out);
  return out;
}

double RobustNoiseSd(std::vector<double>* values) {
  if (values->empty()) return 0.0;
  const auto mid = values->begin() + values->size() / 2;
  std::nth_element(values->begin(), mid, values->end());
  const double median = *mid;
  for (double& x : *values) x = std::abs(x - median);
  std::nth_element(values->begin(), mid, values->end());
  return kMadToSd * *mid;
}

}  // namespace irdist
