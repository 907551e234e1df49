#include "estimator/line_of_sight.h"

#include <algorithm>
#include <cmath>

#include "base/pi.h"
#include "estimator/blur_model.h"

namespace irdist {

namespace {


// The rotation that takes the unit vector `from` onto the optical axis (0, 0, 1) by the smallest
// angle (Rodrigues about from x z).
cv::Matx33d TurnOntoAxis(const cv::Vec3d& from) {
  const cv::Vec3d z(0.0, 0.0, 1.0);
  const cv::Vec3d axis = from.cross(z);
  const double s = cv::norm(axis), c = from.dot(z);
  if (s < 1e-15) return cv::Matx33d::eye();
  const cv::Vec3d k = axis / s;
  const cv::Matx33d kx(0.0, -k[2], k[1], k[2], 0.0, -k[0], -k[1], k[0], 0.0);
  return cv::Matx33d::eye() + s * kx + (1.0 - c) * kx * kx;
}

// The blur inside the frame's moment variances (see ToLineOfSight).
double MomentBlurVarPx2(const Features& f) {
  if (std::isfinite(f.size_blur_var_px2) && f.size_blur_var_px2 > 0.0) return f.size_blur_var_px2;
  if (std::isfinite(f.blur_var_px2) && f.blur_var_px2 > 0.0) return f.blur_var_px2;
  return kPixelAreaVarPx2;
}

// The moment ellipse's principal variances and direction mapped through J, blur kept as it is.
void TurnMoments(const cv::Matx22d& j, Features* f) {
  const double blur = std::min(MomentBlurVarPx2(*f), f->moment_minor_var_px2);
  const double a = f->ellipse_moments.angle_deg * kPi / 180.0;
  const cv::Matx22d rot(std::cos(a), -std::sin(a), std::sin(a), std::cos(a));
  const double l1 = f->moment_major_var_px2 - blur, l2 = f->moment_minor_var_px2 - blur;
  const cv::Matx22d disc = rot * cv::Matx22d(l1, 0.0, 0.0, l2) * rot.t();
  const cv::Matx22d turned = j * disc * j.t();
  const double xx = turned(0, 0), yy = turned(1, 1), xy = 0.5 * (turned(0, 1) + turned(1, 0));
  const double root = std::sqrt(std::max(0.0, 0.25 * (xx - yy) * (xx - yy) + xy * xy));
  const double m1 = 0.5 * (xx + yy) + root, m2 = 0.5 * (xx + yy) - root;
  f->moment_major_var_px2 = m1 + blur;
  f->moment_minor_var_px2 = m2 + blur;
  EllipseFit& e = f->ellipse_moments;
  if (!e.valid) return;
  const bool theta0_from_moments = f->theta0_deg == e.theta0_deg;
  e.angle_deg = 0.5 * std::atan2(2.0 * xy, xx - yy) * 180.0 / kPi;
  if (l1 > 0.0) e.major_px *= std::sqrt(std::max(m1, 0.0) / l1);
  if (l2 > 0.0) e.minor_px *= std::sqrt(std::max(m2, 0.0) / l2);
  if (e.major_px > 0.0) {
    e.theta0_deg = std::acos(std::clamp(e.minor_px / e.major_px, 0.0, 1.0)) * 180.0 / kPi;
  }
  if (theta0_from_moments) f->theta0_deg = e.theta0_deg;
}

// The sums and the spread of the window's gray levels as the turned camera's aperture takes them.
void TurnSignal(double cos_field, Features* f) {
  if (!(f->roi_area_px > 0)) return;
  const double area = static_cast<double>(f->roi_area_px);
  const double mean_signal = (f->f00 - f->background * area) / area;
  const double c2 = cos_field * cos_field;
  const double c5 = c2 * c2 * cos_field;
  const double second = f->sigma * f->sigma + mean_signal * mean_signal;
  f->sigma = std::sqrt(std::max(0.0, second / c5 - mean_signal * mean_signal / c2));
  f->f00 /= cos_field;
  f->e_rel /= cos_field;
}

}  // namespace

LineOfSight LineOfSightAt(const RayOfPixel& ray_of, const cv::Point2d& blob_px, double fx_px,
                          double fy_px) {
  LineOfSight view;
  const cv::Vec3d ray = cv::normalize(ray_of(blob_px));
  view.cos_field = ray[2];
  const cv::Matx33d turn = TurnOntoAxis(ray);
  auto turned_px = [&](const cv::Point2d& p) {
    const cv::Vec3d v = turn * ray_of(p);
    return cv::Vec2d(fx_px * v[0] / v[2], fy_px * v[1] / v[2]);
  };
  constexpr double kStepPx = 0.5;
  const cv::Vec2d du = (turned_px(blob_px + cv::Point2d(kStepPx, 0.0)) -
                        turned_px(blob_px - cv::Point2d(kStepPx, 0.0))) / (2.0 * kStepPx);
  const cv::Vec2d dv = (turned_px(blob_px + cv::Point2d(0.0, kStepPx)) -
                        turned_px(blob_px - cv::Point2d(0.0, kStepPx))) / (2.0 * kStepPx);
  view.jacobian = cv::Matx22d(du[0], dv[0], du[1], dv[1]);
  return view;
}

Features ToLineOfSight(const Features& frame, const LineOfSight& view) {
  Features f = frame;
  if (!f.blob_found || !(view.cos_field > 0.0)) return f;
  if (f.moment_major_var_px2 > 0.0) TurnMoments(view.jacobian, &f);
  TurnSignal(view.cos_field, &f);
  return f;
}

}  // namespace irdist
