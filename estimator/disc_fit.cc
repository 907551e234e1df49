#include "estimator/disc_fit.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "base/pi.h"

namespace irdist {

namespace {


}  // namespace

double Theta0FromAxes(double minor, double major) {
  if (major <= 0.0) return 0.0;
  const double ratio = std::clamp(minor / major, 0.0, 1.0);
  return std::acos(ratio) * 180.0 / kPi;
}

double Theta0FromVariances(double minor_var_px2, double major_var_px2) {
  if (!(major_var_px2 > 0.0)) return std::numeric_limits<double>::quiet_NaN();
  return Theta0FromAxes(std::sqrt(std::max(0.0, minor_var_px2)), std::sqrt(major_var_px2));
}

namespace {

// kModelFit: a uniformly bright elliptical disc {d : d^T P d <= 1} (d = pixel - centre), blurred by
// a Gaussian of sigma s and integrated over each pixel by 3x3 sub-samples. The blurred disc at a
// point is approximated by the blurred straight edge B + A Phi(dist / s), with dist the signed
// distance to the disc's edge to first order, (1 - q) / (2 |P d|), q = d^T P d: exact on the
// edge, and the error away from it sits where Phi is ~0 or ~1 for blobs several blur sigmas wide;
// the edge's curvature shifts the blurred edge inward by kappa s^2 / 2 (modelled).
// Parameters: centre x, y (relative to the fit's origin), P11, P12, P22, s, A, B.
constexpr int kDiscParams = 8;
using DiscVector = cv::Matx<double, kDiscParams, 1>;
using DiscMatrix = cv::Matx<double, kDiscParams, kDiscParams>;

constexpr double kInvSqrt2 = 0.70710678118654752440;
constexpr double kInvSqrt2Pi = 0.39894228040143267794;

// A pixel whose centre lies more than 4 blur sigmas (plus its half-diagonal) inside or outside
// the edge is flat: no sub-sampling. True with its value in *value (and gradient in *jac when
// not null) for such a pixel.
bool FlatDiscPixel(const DiscVector& v, double px, double py, DiscVector* jac, double* value) {
  const double cx = v(0), cy = v(1), p11 = v(2), p12 = v(3), p22 = v(4), s = v(5);
  const double dx = px - cx, dy = py - cy;
  const double gx = p11 * dx + p12 * dy, gy = p12 * dx + p22 * dy;
  const double n = std::sqrt(gx * gx + gy * gy);
  const double dist = n > 1e-12 ? (1.0 - dx * gx - dy * gy) / (2.0 * n) : HUGE_VAL;
  if (!(std::abs(dist) > 4.0 * s + 0.75)) return false;
  const double inside = dist > 0.0 ? 1.0 : 0.0;
  if (jac != nullptr) {
    *jac = DiscVector::zeros();
    (*jac)(6) = inside;
    (*jac)(7) = 1.0;
  }
  *value = v(7) + v(6) * inside;
  return true;
}

// The blurred edge Phi at the sub-sample (dx, dy) from the disc's centre; its gradient with
// respect to the parameters 0-5, times A, added to *g_sum when g_sum is not null.
double DiscSubSample(const DiscVector& v, double dx, double dy, DiscVector* g_sum) {
  const double p11 = v(2), p12 = v(3), p22 = v(4), s = v(5), a = v(6);
  const double gx = p11 * dx + p12 * dy, gy = p12 * dx + p22 * dy;
  const double q = dx * gx + dy * gy;
  const double n = std::sqrt(gx * gx + gy * gy);
  if (n < 1e-12) return 1.0;
  // A convex edge of curvature kappa blurs to Phi((dist - kappa s^2 / 2) / s) to first order:
  // kappa of the level set of q through the point (its derivatives are left out of the
  // Jacobian: a second-order term).
  const double kappa = (n * n * (p11 + p22) - (gx * gx * p11 + 2.0 * gx * gy * p12 +
                                               gy * gy * p22)) / (n * n * n);
  const double dist = (1.0 - q) / (2.0 * n);
  const double z = dist / s - 0.5 * kappa * s;
  if (z > 4.0) return 1.0;
  if (z < -4.0) return 0.0;
  const double phi = 0.5 * std::erfc(-z * kInvSqrt2);
  if (g_sum == nullptr) return phi;
  const double k = a * kInvSqrt2Pi * std::exp(-0.5 * z * z) / s;
  const double inv_n = 1.0 / n;
  const double dq[5] = {-2.0 * gx, -2.0 * gy, dx * dx, 2.0 * dx * dy, dy * dy};
  const double dn[5] = {-(gx * p11 + gy * p12) * inv_n, -(gx * p12 + gy * p22) * inv_n,
                        gx * dx * inv_n, (gx * dy + gy * dx) * inv_n, gy * dy * inv_n};
  for (int j = 0; j < 5; ++j) (*g_sum)(j) += k * (-0.5 * dq[j] * inv_n - dist * dn[j] * inv_n);
  (*g_sum)(5) -= k * (dist / s + 0.5 * kappa * s);
  return phi;
}

// Model value of the pixel centred at (px, py) (relative to the fit's origin); its gradient with
// respect to the parameters in *jac when jac is not null.
double DiscPixel(const DiscVector& v, double px, double py, DiscVector* jac) {
  constexpr double kOffsets[3] = {-1.0 / 3.0, 0.0, 1.0 / 3.0};
  double flat_value = 0.0;
  if (FlatDiscPixel(v, px, py, jac, &flat_value)) return flat_value;
  double sum_phi = 0.0;
  DiscVector g_sum = DiscVector::zeros();
  for (double oy : kOffsets) {
    const double dy = py + oy - v(1);
    for (double ox : kOffsets) {
      sum_phi += DiscSubSample(v, px + ox - v(0), dy, jac != nullptr ? &g_sum : nullptr);
    }
  }
  constexpr double kInvSamples = 1.0 / 9.0;
  const double phi_mean = sum_phi * kInvSamples;
  if (jac != nullptr) {
    *jac = g_sum * kInvSamples;
    (*jac)(6) = phi_mean;
    (*jac)(7) = 1.0;
  }
  return v(7) + v(6) * phi_mean;
}

bool DiscIsValid(const DiscVector& v) {
  return v(2) > 0.0 && v(4) > 0.0 && v(2) * v(4) - v(3) * v(3) > 0.0 && v(5) > 0.05 &&
         v(5) < 20.0 && v(6) > 0.0;
}

// The pixels of `rect` as (x - ox, y - oy, normalised gray level).
std::vector<cv::Vec3d> DiscSamples(const cv::Mat& image, const cv::Rect& rect, double max_gray,
                                   double ox, double oy) {
  std::vector<cv::Vec3d> samples;
  samples.reserve(static_cast<size_t>(rect.area()));
  for (int y = rect.y; y < rect.y + rect.height; ++y) {
    const uint16_t* row = image.ptr<uint16_t>(y);
    for (int x = rect.x; x < rect.x + rect.width; ++x)
      samples.emplace_back(x - ox, y - oy, row[x] / max_gray);
  }
  return samples;
}

// Start: the disc whose covariance is the moments' minus blur and pixel variance (a uniform
// ellipse of semi-axis a has variance a^2 / 4 along it), or the half-maximum contour's ellipse.
DiscVector DiscStart(double max_gray, const DiscMoments& m, const EllipseFit& contour,
                     double background, double peak, double s0) {
  const double remove = s0 * s0 + 1.0 / 12.0;
  const double tr = m.sxx + m.syy;
  const double root = std::sqrt(0.25 * (m.sxx - m.syy) * (m.sxx - m.syy) + m.sxy * m.sxy);
  const double l1 = std::max(0.5 * tr + root - remove, 0.25);
  const double l2 = std::max(0.5 * tr - root - remove, 0.25);
  double phi = 0.5 * std::atan2(2.0 * m.sxy, m.sxx - m.syy);
  double i1 = 1.0 / (4.0 * l1), i2 = 1.0 / (4.0 * l2);
  if (contour.valid && contour.minor_px > 1.0) {
    // The half-maximum contour of a blurred disc lies close to the disc's edge, and noise in the
    // moments' wings does not move it: the better start when it exists.
    phi = contour.angle_deg * kPi / 180.0;
    i1 = 4.0 / (contour.major_px * contour.major_px);
    i2 = 4.0 / (contour.minor_px * contour.minor_px);
  }
  const double c = std::cos(phi), sn = std::sin(phi);
  DiscVector v;
  v(0) = 0.0;
  v(1) = 0.0;
  v(2) = i1 * c * c + i2 * sn * sn;
  v(3) = (i1 - i2) * c * sn;
  v(4) = i1 * sn * sn + i2 * c * c;
  v(5) = s0;
  v(6) = std::max((peak - background) / max_gray, 1e-6);
  v(7) = background / max_gray;
  return v;
}

double DiscCost(const std::vector<cv::Vec3d>& samples, const DiscVector& p) {
  double cost = 0.0;
  for (const cv::Vec3d& s : samples) {
    const double r = DiscPixel(p, s[0], s[1], nullptr) - s[2];
    cost += r * r;
  }
  return cost;
}

// J^T J and J^T r of the disc model at v.
void DiscNormalEquations(const std::vector<cv::Vec3d>& samples, const DiscVector& v,
                         DiscMatrix* jtj, DiscVector* jtr) {
  *jtj = DiscMatrix::zeros();
  *jtr = DiscVector::zeros();
  DiscVector jac;
  for (const cv::Vec3d& s : samples) {
    const double r = DiscPixel(v, s[0], s[1], &jac) - s[2];
    for (int a = 0; a < kDiscParams; ++a) {
      if (jac(a) == 0.0) continue;
      (*jtr)(a) += jac(a) * r;
      for (int b = a; b < kDiscParams; ++b) (*jtj)(a, b) += jac(a) * jac(b);
    }
  }
  for (int a = 0; a < kDiscParams; ++a)
    for (int b = 0; b < a; ++b) (*jtj)(a, b) = (*jtj)(b, a);
}

// One damped step from v (up to 10 tries with growing lambda); returns the relative decrease of
// the cost, or a negative value when no try decreased it. The disc model's validity region
// (positive definite shape, bounded blur) is enforced by rejecting steps that leave it.
double DiscStep(const std::vector<cv::Vec3d>& samples, DiscVector* v, double* cost,
                double* lambda) {
  DiscMatrix jtj;
  DiscVector jtr;
  DiscNormalEquations(samples, *v, &jtj, &jtr);
  for (int attempt = 0; attempt < 10; ++attempt) {
    DiscMatrix damped = jtj;
    for (int a = 0; a < kDiscParams; ++a) damped(a, a) += *lambda * (jtj(a, a) + 1e-12);
    DiscVector step;
    if (!cv::solve(damped, -jtr, step, cv::DECOMP_CHOLESKY)) {
      *lambda *= 10.0;
      continue;
    }
    const DiscVector next = *v + step;
    const double next_cost = DiscIsValid(next) ? DiscCost(samples, next) : HUGE_VAL;
    if (next_cost < *cost) {
      const double relative_change = (*cost - next_cost) / std::max(*cost, 1e-300);
      *v = next;
      *cost = next_cost;
      *lambda = std::max(*lambda * 0.3, 1e-9);
      return relative_change;
    }
    *lambda *= 10.0;
  }
  return -1.0;
}

// The fitted disc's ellipse (centre offset by (ox, oy)); false when its shape is not an ellipse.
bool DiscEllipse(const DiscVector& v, double ox, double oy, EllipseFit* fit) {
  // Axes of the fitted disc: eigenvalues of P are 1 / semi-axis^2.
  const double pt = v(2) + v(4);
  const double pr = std::sqrt(0.25 * (v(2) - v(4)) * (v(2) - v(4)) + v(3) * v(3));
  const double e_small = 0.5 * pt - pr, e_large = 0.5 * pt + pr;
  if (!(e_small > 0.0)) return false;
  fit->valid = true;
  fit->center_px = cv::Point2d(ox + v(0), oy + v(1));
  fit->major_px = 2.0 / std::sqrt(e_small);
  fit->minor_px = 2.0 / std::sqrt(e_large);
  // 0.5 atan2(2 P12, P11 - P22) is the direction of P's larger eigenvalue: the minor axis.
  double angle = 0.5 * std::atan2(2.0 * v(3), v(2) - v(4)) * 180.0 / kPi + 90.0;
  if (angle > 90.0) angle -= 180.0;
  fit->angle_deg = angle;
  fit->theta0_deg = Theta0FromAxes(fit->minor_px, fit->major_px);
  return true;
}

}  // namespace

// Fits the disc model to the pixels of `rect` (normalised gray levels); start from the moment
// ellipse (centre, covariance) with blur s0. Returns false when the fit fails.
bool FitDisc(const cv::Mat& image, const cv::Rect& rect, double max_gray, const DiscMoments& m,
             const EllipseFit& contour, double background, double peak, double s0,
             EllipseFit* fit, double* blur_px, double* rms) {
  const std::vector<cv::Vec3d> samples = DiscSamples(image, rect, max_gray, m.cx, m.cy);
  if (samples.size() < 4 * kDiscParams) return false;
  DiscVector v = DiscStart(max_gray, m, contour, background, peak, s0);
  double cost = DiscCost(samples, v);
  double lambda = 1e-3;
  for (int iteration = 0; iteration < 20; ++iteration) {
    if (DiscStep(samples, &v, &cost, &lambda) < 1e-5) break;  // no decrease, or too small
  }
  if (!DiscIsValid(v) || !DiscEllipse(v, m.cx, m.cy, fit)) return false;
  *blur_px = v(5);
  *rms = std::sqrt(cost / samples.size());
  return true;
}

}  // namespace irdist
