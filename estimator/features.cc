#include "estimator/features.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "base/check.h"

namespace irdist {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Median and median absolute deviation of a strided subsample of a CV_16UC1 image.
void RobustBackground(const cv::Mat& coarse, double* median, double* mad) {
  std::vector<uint16_t> values;
  values.reserve(coarse.total() / 3 + 1);
  for (int y = 0; y < coarse.rows; ++y) {
    const uint16_t* row = coarse.ptr<uint16_t>(y);
    for (int x = (y % 3); x < coarse.cols; x += 3) values.push_back(row[x]);
  }
  IRDIST_CHECK(!values.empty(), "empty image");
  const size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + mid, values.end());
  *median = values[mid];
  for (uint16_t& v : values) v = static_cast<uint16_t>(std::abs(static_cast<int>(v) - *median));
  std::nth_element(values.begin(), values.begin() + mid, values.end());
  *mad = values[mid];
}

cv::Rect SquareAround(double cx, double cy, int side) {
  const int x0 = static_cast<int>(std::lround(cx - 0.5 * (side - 1)));
  const int y0 = static_cast<int>(std::lround(cy - 0.5 * (side - 1)));
  return cv::Rect(x0, y0, side, side);
}

// Background-subtracted first and second moments of the pixels above `threshold` in `rect`.
struct Moments {
  double weight = 0.0, cx = 0.0, cy = 0.0, sxx = 0.0, syy = 0.0, sxy = 0.0;
};

Moments WeightedMoments(const cv::Mat& image, const cv::Rect& rect, double background,
                        double threshold) {
  Moments m;
  double sx = 0.0, sy = 0.0, sxx = 0.0, syy = 0.0, sxy = 0.0;
  for (int y = rect.y; y < rect.y + rect.height; ++y) {
    const uint16_t* row = image.ptr<uint16_t>(y);
    for (int x = rect.x; x < rect.x + rect.width; ++x) {
      const double g = row[x];
      if (g <= threshold) continue;
      const double w = g - background;
      m.weight += w;
      sx += w * x;
      sy += w * y;
      sxx += w * x * x;
      syy += w * y * y;
      sxy += w * x * y;
    }
  }
  if (m.weight <= 0.0) return m;
  m.cx = sx / m.weight;
  m.cy = sy / m.weight;
  m.sxx = sxx / m.weight - m.cx * m.cx;
  m.syy = syy / m.weight - m.cy * m.cy;
  m.sxy = sxy / m.weight - m.cx * m.cy;
  return m;
}

// kAperture: moments of every pixel within `radius` of (cx, cy), background-subtracted with the
// mean of the window's pixels beyond radius + 1 (the blob's support ends well inside the radius).
Moments ApertureMoments(const cv::Mat& image, const cv::Rect& rect, double cx, double cy,
                        double radius, double fallback_background) {
  double outside = 0.0;
  int n_outside = 0;
  const double r_in2 = radius * radius, r_out2 = (radius + 1.0) * (radius + 1.0);
  for (int y = rect.y; y < rect.y + rect.height; ++y) {
    const uint16_t* row = image.ptr<uint16_t>(y);
    for (int x = rect.x; x < rect.x + rect.width; ++x) {
      const double r2 = (x - cx) * (x - cx) + (y - cy) * (y - cy);
      if (r2 > r_out2) {
        outside += row[x];
        ++n_outside;
      }
    }
  }
  const double background = n_outside >= 64 ? outside / n_outside : fallback_background;
  Moments m;
  double sx = 0.0, sy = 0.0, sxx = 0.0, syy = 0.0, sxy = 0.0;
  for (int y = rect.y; y < rect.y + rect.height; ++y) {
    const uint16_t* row = image.ptr<uint16_t>(y);
    const double dy = y - cy;
    for (int x = rect.x; x < rect.x + rect.width; ++x) {
      const double dx = x - cx;
      if (dx * dx + dy * dy > r_in2) continue;
      const double w = row[x] - background;
      m.weight += w;
      sx += w * dx;
      sy += w * dy;
      sxx += w * dx * dx;
      syy += w * dy * dy;
      sxy += w * dx * dy;
    }
  }
  if (m.weight <= 0.0) return m;
  const double mx = sx / m.weight, my = sy / m.weight;
  m.cx = cx + mx;
  m.cy = cy + my;
  m.sxx = sxx / m.weight - mx * mx;
  m.syy = syy / m.weight - my * my;
  m.sxy = sxy / m.weight - mx * my;
  return m;
}

double Theta0FromAxes(double minor, double major) {
  if (major <= 0.0) return 0.0;
  const double ratio = std::clamp(minor / major, 0.0, 1.0);
  return std::acos(ratio) * 180.0 / kPi;
}

}  // namespace

const char* ToString(RoiPolicy policy) {
  switch (policy) {
    case RoiPolicy::kFixedWindow:
      return "fixed_window";
    case RoiPolicy::kThreshold:
      return "threshold";
  }
  return "unknown";
}

const char* ToString(MomentMethod method) {
  switch (method) {
    case MomentMethod::kThreshold:
      return "threshold";
    case MomentMethod::kAperture:
      return "aperture";
  }
  return "unknown";
}

bool ParseMomentMethod(const std::string& name, MomentMethod* method) {
  for (MomentMethod m : {MomentMethod::kThreshold, MomentMethod::kAperture}) {
    if (name == ToString(m)) {
      *method = m;
      return true;
    }
  }
  return false;
}

const char* ToString(EllipseMethod method) {
  switch (method) {
    case EllipseMethod::kMoments:
      return "moments";
    case EllipseMethod::kContour:
      return "contour";
  }
  return "unknown";
}

bool ParseRoiPolicy(const std::string& name, RoiPolicy* policy) {
  for (RoiPolicy p : {RoiPolicy::kFixedWindow, RoiPolicy::kThreshold}) {
    if (name == ToString(p)) {
      *policy = p;
      return true;
    }
  }
  return false;
}

bool ParseEllipseMethod(const std::string& name, EllipseMethod* method) {
  for (EllipseMethod m : {EllipseMethod::kMoments, EllipseMethod::kContour}) {
    if (name == ToString(m)) {
      *method = m;
      return true;
    }
  }
  return false;
}

double InverseResponse::Apply(double x) const {
  if (m.empty()) return x;
  if (x <= m.front()) return f.front();
  if (x >= m.back()) return f.back();
  const size_t k = std::upper_bound(m.begin(), m.end(), x) - m.begin();
  const double u = (x - m[k - 1]) / (m[k] - m[k - 1]);
  return f[k - 1] + u * (f[k] - f[k - 1]);
}

bool InverseResponse::IsValid(std::string* why) const {
  auto fail = [why](const char* text) {
    if (why) *why = text;
    return false;
  };
  if (m.empty() && f.empty()) return true;
  if (m.size() != f.size()) return fail("inverse_response: m and f differ in length");
  if (m.size() < 2) return fail("inverse_response: needs at least two knots");
  for (size_t k = 0; k < m.size(); ++k) {
    if (!(m[k] >= 0.0 && m[k] <= 1.0)) return fail("inverse_response: knots m must lie in [0,1]");
    if (k > 0 && !(m[k] > m[k - 1])) return fail("inverse_response: m must increase strictly");
    if (k > 0 && !(f[k] >= f[k - 1])) return fail("inverse_response: f must be monotone");
  }
  return true;
}

bool FeatureOptions::IsValid(std::string* why) const {
  auto fail = [why](const char* text) {
    if (why) *why = text;
    return false;
  };
  if (window_side_px < 8 || window_side_px > 1024)
    return fail("window_side_px must be in [8,1024]");
  if (!(threshold_fraction > 0.0 && threshold_fraction < 1.0))
    return fail("threshold_fraction must be in (0,1)");
  if (!(moment_threshold_fraction >= 0.0 && moment_threshold_fraction < 1.0))
    return fail("moment_threshold_fraction must be in [0,1)");
  if (!(psf_sigma_px >= 0.0)) return fail("psf_sigma_px must be >= 0");
  if (!(aperture_margin_px >= 0.0)) return fail("aperture_margin_px must be >= 0");
  if (detection_downsample < 1 || detection_downsample > 16)
    return fail("detection_downsample must be in [1,16]");
  if (!(min_contrast_fraction > 0.0 && min_contrast_fraction < 1.0))
    return fail("min_contrast_fraction must be in (0,1)");
  return inverse_response.IsValid(why);
}

std::string Features::BriefReport() const {
  std::ostringstream out;
  if (!blob_found) return "no blob found";
  out << "blob at (" << centroid_px.x << ", " << centroid_px.y << ") px, ROI " << roi.width << "x"
      << roi.height << " A=" << roi_area_px << ": E_rel=" << e_rel << " F(0,0)=" << f00
      << " Sigma=" << sigma << " theta0=" << theta0_deg << " deg";
  if (saturated_pixels > 0) out << " SATURATED(" << saturated_pixels << " px)";
  if (touches_border) out << " BORDER";
  if (blob_clipped_by_roi) out << " CLIPPED_BY_ROI";
  return out.str();
}

FeatureOptions PaperFeatureOptions() {
  FeatureOptions options;
  options.roi_policy = RoiPolicy::kFixedWindow;
  options.window_side_px = 64;
  return options;
}

Features ComputeFeatures(const cv::Mat& image, int bit_depth, const FeatureOptions& options) {
  std::string why;
  IRDIST_CHECK(options.IsValid(&why), why);
  IRDIST_CHECK(image.type() == CV_16UC1, "ComputeFeatures needs a CV_16UC1 image, got type ",
               image.type());
  IRDIST_CHECK(bit_depth >= 8 && bit_depth <= 16, "bit_depth must be in [8,16], got ", bit_depth);
  IRDIST_CHECK(image.rows >= options.window_side_px && image.cols >= options.window_side_px,
               "image smaller than the ROI window");
  Features out;
  out.bit_depth = bit_depth;
  const double max_gray = static_cast<double>((1 << bit_depth) - 1);
  const cv::Rect frame(0, 0, image.cols, image.rows);

  // 1. Coarse pass: area-average downsampling, robust background, brightest coarse cell.
  const int k = options.detection_downsample;
  cv::Mat coarse;
  if (k > 1) {
    cv::resize(image, coarse, cv::Size(image.cols / k, image.rows / k), 0, 0, cv::INTER_AREA);
  } else {
    coarse = image;
  }
  double background = 0.0, mad = 0.0;
  RobustBackground(coarse, &background, &mad);
  double coarse_peak = 0.0;
  cv::Point coarse_at;
  cv::minMaxLoc(coarse, nullptr, &coarse_peak, nullptr, &coarse_at);
  const double min_contrast =
      std::max(options.min_contrast_fraction * max_gray, 8.0 * 1.4826 * mad);
  out.background = background / max_gray;
  if (coarse_peak - background < min_contrast) return out;  // no blob

  // 2. Full resolution, in a window around the coarse peak: peak and intensity centroid.
  const int side = options.window_side_px;
  double cx = coarse_at.x * k + 0.5 * (k - 1);
  double cy = coarse_at.y * k + 0.5 * (k - 1);
  double peak = 0.0;
  cv::Rect window;
  for (int iteration = 0; iteration < 4; ++iteration) {
    window = SquareAround(cx, cy, side) & frame;
    cv::Point at;
    cv::minMaxLoc(image(window), nullptr, &peak, nullptr, &at);
    const double threshold = background + options.moment_threshold_fraction * (peak - background);
    const Moments m = WeightedMoments(image, window, background, threshold);
    if (m.weight <= 0.0) return out;
    const double shift = std::hypot(m.cx - cx, m.cy - cy);
    cx = m.cx;
    cy = m.cy;
    if (shift < 0.25) break;
  }
  out.blob_found = true;
  out.peak = peak / max_gray;
  out.centroid_px = cv::Point2d(cx, cy);

  const cv::Rect full_window = SquareAround(cx, cy, side);
  window = full_window & frame;
  const double moment_threshold =
      background + options.moment_threshold_fraction * (peak - background);
  const double roi_threshold = background + options.threshold_fraction * (peak - background);
  const double half_threshold = background + 0.5 * (peak - background);

  // 3. Border flags: a clipped window, or blob pixels on the outermost image rows/columns, or on
  // the edge of the fixed window.
  out.touches_border = window != full_window;
  for (int y = window.y; y < window.y + window.height; ++y) {
    const uint16_t* row = image.ptr<uint16_t>(y);
    for (int x = window.x; x < window.x + window.width; ++x) {
      if (row[x] <= roi_threshold) continue;
      const bool on_image_edge = x == 0 || y == 0 || x == image.cols - 1 || y == image.rows - 1;
      const bool on_window_edge = x == window.x || y == window.y ||
                                  x == window.x + window.width - 1 ||
                                  y == window.y + window.height - 1;
      if (on_image_edge) out.touches_border = true;
      if (on_window_edge && options.roi_policy == RoiPolicy::kFixedWindow)
        out.blob_clipped_by_roi = true;
    }
  }

  // 4. ROI statistics: E_rel, F(0,0), Sigma, saturation.
  const bool fixed = options.roi_policy == RoiPolicy::kFixedWindow;
  const InverseResponse& f = options.inverse_response;
  const uint16_t saturated_level = static_cast<uint16_t>(max_gray);
  double sum = 0.0, sum_sq = 0.0, sum_f = 0.0;
  int area = 0, saturated = 0;
  int min_x = image.cols, min_y = image.rows, max_x = -1, max_y = -1;
  for (int y = window.y; y < window.y + window.height; ++y) {
    const uint16_t* row = image.ptr<uint16_t>(y);
    for (int x = window.x; x < window.x + window.width; ++x) {
      if (!fixed && row[x] <= roi_threshold) continue;
      const double mv = row[x] / max_gray;
      sum += mv;
      sum_sq += mv * mv;
      sum_f += f.IsIdentity() ? mv : f.Apply(mv);
      ++area;
      if (row[x] >= saturated_level) ++saturated;
      min_x = std::min(min_x, x);
      max_x = std::max(max_x, x);
      min_y = std::min(min_y, y);
      max_y = std::max(max_y, y);
    }
  }
  if (area == 0) {
    out.blob_found = false;
    return out;
  }
  out.roi = fixed ? window : cv::Rect(min_x, min_y, max_x - min_x + 1, max_y - min_y + 1);
  out.roi_area_px = area;
  out.saturated_pixels = saturated;
  out.f00 = sum;
  out.e_rel = sum_f / area;
  const double mean = sum / area;
  out.sigma = std::sqrt(std::max(0.0, sum_sq / area - mean * mean));

  // 5. Ellipse from background-subtracted second moments.
  Moments m = WeightedMoments(image, window, background, moment_threshold);
  if (options.moment_method == MomentMethod::kAperture && m.weight > 0.0) {
    // Support: the farthest pixel above the moment threshold from the thresholded centroid.
    double support2 = 0.0;
    for (int y = window.y; y < window.y + window.height; ++y) {
      const uint16_t* row = image.ptr<uint16_t>(y);
      for (int x = window.x; x < window.x + window.width; ++x) {
        if (row[x] <= moment_threshold) continue;
        support2 = std::max(support2, (x - m.cx) * (x - m.cx) + (y - m.cy) * (y - m.cy));
      }
    }
    const Moments a = ApertureMoments(image, window, m.cx, m.cy,
                                      std::sqrt(support2) + options.aperture_margin_px, background);
    if (a.weight > 0.0 && a.sxx > 0.0 && a.syy > 0.0) m = a;
  }
  {
    const double tr = m.sxx + m.syy;
    const double det_root =
        std::sqrt(std::max(0.0, 0.25 * (m.sxx - m.syy) * (m.sxx - m.syy) + m.sxy * m.sxy));
    const double l1 = 0.5 * tr + det_root;
    const double l2 = 0.5 * tr - det_root;
    out.moment_major_var_px2 = l1;
    out.moment_minor_var_px2 = l2;
    const double blur2 = options.psf_sigma_px * options.psf_sigma_px;
    EllipseFit& e = out.ellipse_moments;
    if (l1 - blur2 > 0.0) {
      e.valid = true;
      e.center_px = cv::Point2d(m.cx, m.cy);
      // A uniform ellipse of semi-axis a has variance a^2/4 along it: full axis = 4 sqrt(var).
      e.major_px = 4.0 * std::sqrt(l1 - blur2);
      e.minor_px = 4.0 * std::sqrt(std::max(0.0, l2 - blur2));
      e.angle_deg = 0.5 * std::atan2(2.0 * m.sxy, m.sxx - m.syy) * 180.0 / kPi;
      e.theta0_deg = Theta0FromAxes(e.minor_px, e.major_px);
    }
  }

  // 6. Ellipse from the half-maximum contour (cv::fitEllipse).
  {
    cv::Mat mask;
    cv::Mat window_image = image(window);
    cv::compare(window_image, cv::Scalar(half_threshold), mask, cv::CMP_GT);
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
    if (best < contours.size() && contours[best].size() >= 5) {
      const cv::RotatedRect r = cv::fitEllipse(contours[best]);
      EllipseFit& e = out.ellipse_contour;
      e.valid = true;
      e.center_px = cv::Point2d(r.center.x + window.x, r.center.y + window.y);
      e.major_px = std::max(r.size.width, r.size.height);
      e.minor_px = std::min(r.size.width, r.size.height);
      e.angle_deg = r.size.width >= r.size.height ? r.angle : r.angle + 90.0;
      e.theta0_deg = Theta0FromAxes(e.minor_px, e.major_px);
    }
  }
  const EllipseFit& chosen =
      options.ellipse_method == EllipseMethod::kMoments ? out.ellipse_moments : out.ellipse_contour;
  out.theta0_deg = chosen.theta0_deg;
  return out;
}

}  // namespace irdist
