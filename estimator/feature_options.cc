#include "estimator/features.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>

#include "base/check.h"

// The features' options and names (ToString, Parse*), the inverse response, the paper's options,
// the report, and the linearised frame of ResponseScope::kAllPixels: estimator/features.h's
// declarations other than the computation itself (features.cc).

namespace irdist {

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

const char* ToString(ResponseScope scope) {
  switch (scope) {
    case ResponseScope::kERelOnly:
      return "e_rel_only";
    case ResponseScope::kAllPixels:
      return "all_pixels";
  }
  return "unknown";
}

bool ParseResponseScope(const std::string& name, ResponseScope* scope) {
  for (ResponseScope s : {ResponseScope::kERelOnly, ResponseScope::kAllPixels}) {
    if (name == ToString(s)) {
      *scope = s;
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
    case EllipseMethod::kModelFit:
      return "model_fit";
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
  for (EllipseMethod m :
       {EllipseMethod::kMoments, EllipseMethod::kContour, EllipseMethod::kModelFit}) {
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
  if (!inverse_response.IsValid(why)) return false;
  if (response_scope == ResponseScope::kAllPixels && !inverse_response.IsIdentity() &&
      !(inverse_response.Apply(1.0) > inverse_response.Apply(0.0)))
    return fail("inverse_response: all_pixels scope needs f(1) > f(0)");
  return true;
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
  options.subtract_background = false;  // the paper's E_rel and F(0,0): every pixel as it is
  return options;
}

cv::Mat LineariseFrame(const cv::Mat& image, int bit_depth, const InverseResponse& curve) {
  std::string why;
  IRDIST_CHECK(curve.IsValid(&why), why);
  IRDIST_CHECK(!curve.IsIdentity(), "LineariseFrame needs a curve, not the identity");
  IRDIST_CHECK(image.type() == CV_16UC1, "LineariseFrame needs a CV_16UC1 image, got type ",
               image.type());
  IRDIST_CHECK(bit_depth >= 8 && bit_depth <= 16, "bit_depth must be in [8,16], got ", bit_depth);
  const double f0 = curve.Apply(0.0), f1 = curve.Apply(1.0);
  IRDIST_CHECK(f1 > f0, "inverse response is flat: f(1) == f(0)");
  const int levels = 1 << bit_depth;
  const double max_gray = levels - 1.0;
  std::vector<std::uint16_t> table(static_cast<size_t>(levels));
  for (int g = 0; g < levels; ++g) {
    const double l = std::clamp((curve.Apply(g / max_gray) - f0) / (f1 - f0), 0.0, 1.0);
    table[static_cast<size_t>(g)] = static_cast<std::uint16_t>(std::lround(65535.0 * l));
  }
  // Values above the format's range (stray high bits) map to full scale.
  const std::uint16_t top = table.back();
  cv::Mat out(image.size(), CV_16UC1);
  for (int y = 0; y < image.rows; ++y) {
    const std::uint16_t* src = image.ptr<std::uint16_t>(y);
    std::uint16_t* dst = out.ptr<std::uint16_t>(y);
    for (int x = 0; x < image.cols; ++x) dst[x] = src[x] < levels ? table[src[x]] : top;
  }
  return out;
}

}  // namespace irdist
