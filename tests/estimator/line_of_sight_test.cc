// The camera turned onto the IRED's line of sight (estimator/line_of_sight.h) against a pinhole's
// exact image of a tilted disc off the axis: the disc's rim projected point by point (no local
// map), its image's area moments by Green's theorem, its flux and second moment under the
// pinhole's cos^4 irradiance by quadrature. The turned features must be the on-axis disc's at the
// same range and tilt.
#include "estimator/line_of_sight.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "base/pi.h"

namespace irdist {
namespace {

constexpr double kDeg = kPi / 180.0;
constexpr double kFocalPx = 3000.0;  // principal point at (0, 0)
constexpr double kRadiusMm = 5.0;
constexpr double kRangeMm = 2000.0;
constexpr double kBlurVarPx2 = 0.5;
constexpr int kWindowAreaPx = 64 * 64;

cv::Vec3d PinholeRay(const cv::Point2d& p) {
  return cv::normalize(cv::Vec3d(p.x / kFocalPx, p.y / kFocalPx, 1.0));
}

// The disc's image: its rim through the pinhole, a polygon of `n` vertices.
std::vector<cv::Point2d> DiscImage(double field_deg, double azimuth_deg, double theta_deg,
                                   double tilt_dir_deg, int n = 4096) {
  const double a = field_deg * kDeg, phi = azimuth_deg * kDeg;
  const cv::Vec3d sight(std::sin(a) * std::cos(phi), std::sin(a) * std::sin(phi), std::cos(a));
  const cv::Vec3d centre = kRangeMm * sight;
  // Two directions across the line of sight; the disc's normal leans theta from -sight towards
  // their combination at tilt_dir.
  const cv::Vec3d u = cv::normalize(sight.cross(cv::Vec3d(0.0, 1.0, 0.0)));
  const cv::Vec3d v = sight.cross(u);
  const double t = theta_deg * kDeg, psi = tilt_dir_deg * kDeg;
  const cv::Vec3d lean = std::cos(psi) * u + std::sin(psi) * v;
  const cv::Vec3d normal = -std::cos(t) * sight + std::sin(t) * lean;
  const cv::Vec3d e1 = cv::normalize(normal.cross(u + 0.3 * v));
  const cv::Vec3d e2 = normal.cross(e1);
  std::vector<cv::Point2d> polygon;
  for (int k = 0; k < n; ++k) {
    const double s = 2.0 * kPi * k / n;
    const cv::Vec3d p = centre + kRadiusMm * (std::cos(s) * e1 + std::sin(s) * e2);
    polygon.emplace_back(kFocalPx * p[0] / p[2], kFocalPx * p[1] / p[2]);
  }
  double twice_area = 0.0;  // counter-clockwise, for the signed integrals below
  for (int k = 0; k < n; ++k) twice_area += polygon[k].cross(polygon[(k + 1) % n]);
  if (twice_area < 0.0) std::reverse(polygon.begin(), polygon.end());
  return polygon;
}

struct AreaMoments {
  double area = 0.0;
  cv::Point2d centre;
  double xx = 0.0, yy = 0.0, xy = 0.0;  // central, per unit area
};

// Area moments of a simple polygon (Green's theorem).
AreaMoments MomentsOf(const std::vector<cv::Point2d>& poly) {
  double a = 0.0, cx = 0.0, cy = 0.0, ixx = 0.0, iyy = 0.0, ixy = 0.0;
  for (size_t i = 0; i < poly.size(); ++i) {
    const cv::Point2d p = poly[i], q = poly[(i + 1) % poly.size()];
    const double c = p.x * q.y - q.x * p.y;
    a += c;
    cx += (p.x + q.x) * c;
    cy += (p.y + q.y) * c;
    ixx += (p.x * p.x + p.x * q.x + q.x * q.x) * c;
    iyy += (p.y * p.y + p.y * q.y + q.y * q.y) * c;
    ixy += (p.x * q.y + 2 * p.x * p.y + 2 * q.x * q.y + q.x * p.y) * c;
  }
  AreaMoments m;
  m.area = 0.5 * a;
  m.centre = {cx / (3.0 * a), cy / (3.0 * a)};
  m.xx = ixx / (6.0 * a) - m.centre.x * m.centre.x;
  m.yy = iyy / (6.0 * a) - m.centre.y * m.centre.y;
  m.xy = ixy / (12.0 * a) - m.centre.x * m.centre.y;
  return m;
}

// The pinhole's irradiance per unit radiance at an image point: cos^4 of its field angle.
double Irradiance(const cv::Point2d& p) { return std::pow(PinholeRay(p)[2], 4); }

// Integrals of E and E^2 over the polygon: fan triangles from its centre, each by the 3-point
// rule at its edges' midpoints (exact for quadratics; E varies by < 1e-3 across the blob).
void FluxOf(const std::vector<cv::Point2d>& poly, const cv::Point2d& c, double* e1, double* e2) {
  *e1 = *e2 = 0.0;
  for (size_t i = 0; i < poly.size(); ++i) {
    const cv::Point2d p = poly[i], q = poly[(i + 1) % poly.size()];
    const double area = 0.5 * ((p.x - c.x) * (q.y - c.y) - (q.x - c.x) * (p.y - c.y));
    for (const cv::Point2d& m : {0.5 * (p + q), 0.5 * (p + c), 0.5 * (q + c)}) {
      const double e = Irradiance(m);
      *e1 += area * e / 3.0;
      *e2 += area * e * e / 3.0;
    }
  }
}

// The frame's features of the polygon's blob: moments with the blur added, a unit radiance's
// flux in a window of kWindowAreaPx on a zero background.
Features FrameOf(const std::vector<cv::Point2d>& poly) {
  const AreaMoments m = MomentsOf(poly);
  Features f;
  f.blob_found = true;
  f.centroid_px = m.centre;
  const double root = std::sqrt(0.25 * (m.xx - m.yy) * (m.xx - m.yy) + m.xy * m.xy);
  f.moment_major_var_px2 = 0.5 * (m.xx + m.yy) + root + kBlurVarPx2;
  f.moment_minor_var_px2 = 0.5 * (m.xx + m.yy) - root + kBlurVarPx2;
  f.size_blur_var_px2 = kBlurVarPx2;
  f.ellipse_moments.valid = true;
  f.ellipse_moments.center_px = m.centre;
  f.ellipse_moments.angle_deg = 0.5 * std::atan2(2.0 * m.xy, m.xx - m.yy) / kDeg;
  f.ellipse_moments.major_px = 4.0 * std::sqrt(f.moment_major_var_px2 - kBlurVarPx2);
  f.ellipse_moments.minor_px = 4.0 * std::sqrt(f.moment_minor_var_px2 - kBlurVarPx2);
  f.ellipse_moments.theta0_deg =
      std::acos(f.ellipse_moments.minor_px / f.ellipse_moments.major_px) / kDeg;
  f.theta0_deg = f.ellipse_moments.theta0_deg;
  double e1 = 0.0, e2 = 0.0;
  FluxOf(poly, m.centre, &e1, &e2);
  f.roi_area_px = kWindowAreaPx;
  f.f00 = e1;
  f.e_rel = e1 / kWindowAreaPx;
  const double mean = e1 / kWindowAreaPx;
  f.sigma = std::sqrt(e2 / kWindowAreaPx - mean * mean);
  return f;
}

LineOfSight PinholeView(const Features& f) {
  return LineOfSightAt(PinholeRay, f.centroid_px, kFocalPx, kFocalPx);
}

TEST(LineOfSight, OnTheAxisNothingTurns) {
  const LineOfSight view = LineOfSightAt(PinholeRay, {0.0, 0.0}, kFocalPx, kFocalPx);
  EXPECT_DOUBLE_EQ(view.cos_field, 1.0);
  for (int i = 0; i < 2; ++i) {
    for (int j = 0; j < 2; ++j) EXPECT_NEAR(view.jacobian(i, j), i == j ? 1.0 : 0.0, 1e-9);
  }
}

TEST(LineOfSight, TheFieldAngleIsTheRays) {
  const double field = 20.0 * kDeg;
  const cv::Point2d p(kFocalPx * std::tan(field) * 0.6, kFocalPx * std::tan(field) * 0.8);
  EXPECT_NEAR(LineOfSightAt(PinholeRay, p, kFocalPx, kFocalPx).cos_field, std::cos(field), 1e-12);
}

// The on-axis disc at kRangeMm tilted theta: semi-axes R f / r and R f cos(theta) / r, variances
// a^2 / 4; flux pi a b (unit radiance); second moment pi a b over the window.
struct OnAxis {
  double major_var, minor_var, flux, sigma;
};
OnAxis OnAxisDisc(double theta_deg) {
  const double a = kRadiusMm * kFocalPx / kRangeMm, b = a * std::cos(theta_deg * kDeg);
  const double area = kPi * a * b, mean = area / kWindowAreaPx;
  return {a * a / 4.0, b * b / 4.0, area, std::sqrt(area / kWindowAreaPx - mean * mean)};
}

TEST(LineOfSight, TheTurnedDiscIsTheOnAxisDiscAtItsRangeAndTilt) {
  for (double field : {5.0, 15.0, 30.0}) {
    for (double theta : {0.0, 15.0, 30.0}) {
      for (double tilt_dir : {0.0, 60.0, 90.0}) {
        SCOPED_TRACE(testing::Message() << "field " << field << " theta " << theta << " dir "
                                        << tilt_dir);
        const Features frame = FrameOf(DiscImage(field, 35.0, theta, tilt_dir));
        const Features turned = ToLineOfSight(frame, PinholeView(frame));
        const OnAxis want = OnAxisDisc(theta);
        // The frame's own moments are off by the field's stretch (> 0.7% at 5 deg).
        EXPECT_GT(std::fabs(frame.moment_major_var_px2 - kBlurVarPx2 - want.major_var),
                  5e-3 * want.major_var);
        EXPECT_NEAR(turned.moment_major_var_px2 - kBlurVarPx2, want.major_var,
                    2e-5 * want.major_var);
        EXPECT_NEAR(turned.moment_minor_var_px2 - kBlurVarPx2, want.minor_var,
                    2e-5 * want.major_var);
        EXPECT_NEAR(turned.ellipse_moments.theta0_deg, theta, theta > 0.0 ? 0.01 : 0.3);
        EXPECT_NEAR(turned.theta0_deg, turned.ellipse_moments.theta0_deg, 1e-12);
        EXPECT_NEAR(turned.f00, want.flux, 1e-5 * want.flux);
        EXPECT_NEAR(turned.e_rel, want.flux / kWindowAreaPx, 1e-5 * want.flux / kWindowAreaPx);
        EXPECT_NEAR(turned.sigma, want.sigma, 1e-5 * want.sigma);
        EXPECT_EQ(turned.centroid_px, frame.centroid_px);  // the frame's, for the position
      }
    }
  }
}

TEST(LineOfSight, AFrameWithoutABlobStaysAsItIs) {
  Features none;
  none.f00 = 3.0;
  const LineOfSight view = PinholeView(FrameOf(DiscImage(20.0, 0.0, 0.0, 0.0)));
  EXPECT_EQ(ToLineOfSight(none, view).f00, 3.0);
}

}  // namespace
}  // namespace irdist
