#include "estimator/blob_fit.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/Dense>
#include <ceres/tiny_solver.h>

namespace irdist {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kPixelAreaVarPx2 = 1.0 / 12.0;
// A pass stops when a step changes the chi^2 by less than this: a parameter then moves by about
// 1% of its standard error (TinySolver's function tolerance is absolute, in |f|^2 units).
constexpr double kChi2Tolerance = 1e-4;
// The pixel's spread PixelMean folds into the blur: 5/64 px^2 per axis, the variance of a 4x4 grid
// of sub-samples (offsets +-1/8, +-3/8), against the box's 1/12. The fit integrated each pixel on
// that grid until the model went to one evaluation per pixel (for speed, issue 11); with this
// spread the two agree to 3e-4 of the size variance on a 5 px disc and 1e-4 from 15 px, and the
// accuracy study's figures did not move. With 1/12, discs of 5-8 px came out 0.1% smaller: the
// first-order edge model's own error, which grows with blur / radius, is partly offset by the
// smaller spread (docs/estimator.md "The blob fit").
constexpr double kPixelSpreadVarPx2 = 5.0 / 64.0;
// Parameters: centre x, y (relative to the fit's origin), P11, P12, P22, amplitude, background.
constexpr int kParams = 7;
// A round blob's fitted |a|^2 (anisotropy, below) is exponential with mean E |a_noise|^2: it
// exceeds 4x that mean in e^-4 = 1.8% of frames. Below it the blob is taken as a circle; above,
// only the noise's mean is removed, so a clearly elliptical blob keeps its axes (unbiased |a|^2).
// A soft shrink (|a|^2 less 3x the noise) reached the same dispersion at theta 0 but shortened |a|
// at 10-20 deg (theta max on Fig. 13 0.431 -> 0.444 deg); subtracting 1x alone removes the bias
// but not the scatter (docs/estimator.md).
constexpr double kCircleNoiseMultiple = 4.0;

// The quantities of one pixel's edge geometry PixelMean and its derivatives share.
struct EdgeGeometry {
  double dx, dy, gx, gy, pgx, pgy, r, n, dist, kappa, z;
};

// d Phi(z) / d (x, y, P11, P12, P22) at one pixel (PixelMean's model), by the chain rule through
// q = (p - c)^T P (p - c), g = P (p - c), n = |g|, dist = (sqrt q - q) / n and the curvature
// kappa = (n^2 tr P - g^T P g) / n^3.
void DiscDerivatives(const double* v, const EdgeGeometry& e, double s, double* d) {
  const double phi_over_s = std::exp(-0.5 * e.z * e.z) * 0.39894228040143267794 / s;
  const double n2 = e.n * e.n, inv_n = 1.0 / e.n, inv_n3 = inv_n / n2;
  const double trace = v[2] + v[4];
  const double dq[5] = {-2.0 * e.gx, -2.0 * e.gy, e.dx * e.dx, 2.0 * e.dx * e.dy, e.dy * e.dy};
  const double dgx[5] = {-v[2], -v[3], e.dx, e.dy, 0.0};
  const double dgy[5] = {-v[3], -v[4], 0.0, e.dx, e.dy};
  const double dtrace[5] = {0.0, 0.0, 1.0, 0.0, 1.0};
  const double dgpg_p[5] = {0.0, 0.0, e.gx * e.gx, 2.0 * e.gx * e.gy, e.gy * e.gy};
  const double dq_factor = 0.5 / e.r - 1.0;
  for (int k = 0; k < 5; ++k) {
    const double dn = (e.gx * dgx[k] + e.gy * dgy[k]) * inv_n;
    const double ddist = (dq[k] * dq_factor - e.dist * dn) * inv_n;
    const double dgpg = 2.0 * (e.pgx * dgx[k] + e.pgy * dgy[k]) + dgpg_p[k];
    const double dkappa =
        (2.0 * e.n * dn * trace + n2 * dtrace[k] - dgpg) * inv_n3 - 3.0 * e.kappa * dn * inv_n;
    d[k] = phi_over_s * (ddist - 0.5 * s * s * dkappa);
  }
}

// The blurred disc's mean over the pixel at (x, y), relative to its amplitude, and, when d is
// set, its derivatives along the centre and P (d[0..4]: x, y, P11, P12, P22), analytic: Phi of
// the signed distance to the edge (to first order in the quadratic form, exact on a circle),
// shifted inward by the edge's curvature kappa s^2 / 2 (the blurred edge of a disc of radius R
// sits s^2 / (2R) inside it).
// s: the blur sd with the pixel's spread folded in (kPixelSpreadVarPx2): one evaluation per pixel.
// A pixel's projection on any direction has a variance that does not depend on the direction,
// so a pixel integrates a blurred edge as a wider Gaussian does, up to its kurtosis, which is
// symmetric across the edge and so leaves the edge, the size, in place.
// A pixel more than 5 sd (Phi(-5) = 3e-7, against a 12-bit quantum of 2.4e-4) plus 0.5 px (the
// first-order distance and the curvature's shift) from the edge is 1 or 0, with no derivative.
double PixelMean(const double* v, double x, double y, double s, double* d) {
  const double dx = x - v[0], dy = y - v[1];
  const double gx = v[2] * dx + v[3] * dy, gy = v[3] * dx + v[4] * dy;  // g = P (p - c)
  const double q = dx * gx + dy * gy;
  const double n2 = gx * gx + gy * gy;
  const double r = std::sqrt(q), n = std::sqrt(n2);
  const double dist = (r - q) / n;
  const double margin = 0.5 + 5.0 * s;
  if (q < 0.09 || dist > margin || dist < -margin) {  // well inside (q < 0.09), or far from the edge
    if (d != nullptr) std::fill(d, d + 5, 0.0);
    return dist < 0.0 ? 0.0 : 1.0;
  }
  const double pgx = v[2] * gx + v[3] * gy, pgy = v[3] * gx + v[4] * gy;  // P g
  const double trace = v[2] + v[4], gpg = gx * pgx + gy * pgy;
  const double inv_n = 1.0 / n, inv_n3 = inv_n / n2;
  const double kappa = (n2 * trace - gpg) * inv_n3;
  const double z = (dist - 0.5 * kappa * s * s) / s;
  if (d != nullptr) DiscDerivatives(v, {dx, dy, gx, gy, pgx, pgy, r, n, dist, kappa, z}, s, d);
  return 0.5 * std::erfc(-z * 0.70710678118654752440);
}

struct Pixel {
  double x, y, value;
};

// Every pixel's residual, divided by its noise sd, and the analytic Jacobian, for
// ceres::TinySolver (a dense Levenberg-Marquardt for a few parameters: the general ceres::Problem
// cost more per iteration than the model itself). The model (each pixel's mean and its
// derivatives) is computed once per point and kept; the weights are applied as it is read. So
// TinySolver's Jacobian at an accepted trial step, the next pass's start (new weights, same
// point), the noise regression and the covariance at a pass's solution cost no evaluation.
class WindowResiduals {
 public:
  using Scalar = double;
  enum { NUM_RESIDUALS = Eigen::Dynamic, NUM_PARAMETERS = kParams };

  WindowResiduals(const std::vector<Pixel>& pixels, double edge_sd)
      : pixels_(pixels), edge_sd_(edge_sd), inv_sd_(pixels.size()), mean_(pixels.size()),
        d_mean_(pixels.size() * 5) {}
  // Each pixel's noise variance (the residuals' weights, 1 / sd).
  void SetVariances(const std::vector<double>& var) {
    for (size_t i = 0; i < var.size(); ++i) inv_sd_[i] = 1.0 / std::sqrt(var[i]);
  }
  int NumResiduals() const { return static_cast<int>(pixels_.size()); }
  // The Jacobian is column-major, NumResiduals() x kParams, as TinySolver lays it out.
  bool operator()(const double* v, double* residuals, double* jacobian) const {
    const std::vector<double>& mean = MeansAt(v);
    const size_t n = pixels_.size();
    for (size_t i = 0; i < n; ++i) {
      residuals[i] = (v[6] + v[5] * mean[i] - pixels_[i].value) * inv_sd_[i];
      if (jacobian == nullptr) continue;
      for (int k = 0; k < 5; ++k) jacobian[k * n + i] = v[5] * d_mean_[k * n + i] * inv_sd_[i];
      jacobian[5 * n + i] = mean[i] * inv_sd_[i];
      jacobian[6 * n + i] = inv_sd_[i];
    }
    return true;
  }
  // Each pixel's model mean (relative to the amplitude) at v; nothing is computed when v is the
  // last point.
  const std::vector<double>& MeansAt(const double* v) const {
    if (!computed_ || !std::equal(v, v + kParams, at_)) Compute(v);
    return mean_;
  }

 private:
  void Compute(const double* v) const {
    const size_t n = pixels_.size();
    double d[5];
    for (size_t i = 0; i < n; ++i) {
      mean_[i] = PixelMean(v, pixels_[i].x, pixels_[i].y, edge_sd_, d);
      for (int k = 0; k < 5; ++k) d_mean_[k * n + i] = d[k];
    }
    std::copy(v, v + kParams, at_);
    computed_ = true;
  }

  const std::vector<Pixel>& pixels_;
  double edge_sd_;
  std::vector<double> inv_sd_;
  // The last point computed and its model (TinySolver holds the functor const).
  mutable std::vector<double> mean_, d_mean_;
  mutable double at_[kParams] = {};
  mutable bool computed_ = false;
};

// The disc's start from the moment ellipse: covariance = moments - blur, P = (4 C)^-1.
bool StartFromMoments(const Features& f, double blur_var_px2, cv::Point origin, double* v) {
  const double major = f.moment_major_var_px2 - blur_var_px2;
  const double minor = f.moment_minor_var_px2 - blur_var_px2;
  if (!(major > 0.25) || !(minor > 0.05)) return false;
  const double a = f.ellipse_moments.angle_deg * kPi / 180.0;
  const double c = std::cos(a), s = std::sin(a);
  const double i1 = 1.0 / (4.0 * major), i2 = 1.0 / (4.0 * minor);
  v[0] = f.ellipse_moments.center_px.x - origin.x;
  v[1] = f.ellipse_moments.center_px.y - origin.y;
  v[2] = i1 * c * c + i2 * s * s;
  v[3] = (i1 - i2) * c * s;
  v[4] = i1 * s * s + i2 * c * c;
  v[5] = std::max(1e-6, f.peak - f.background);
  v[6] = f.background;
  return true;
}

// The pixels of a square around the blob reaching 4 blur sigmas + 2 px beyond its major semi-axis.
std::vector<Pixel> BlobPixels(const cv::Mat& image, int bit_depth, const Features& f,
                              double blur_var_px2, cv::Point* origin) {
  const double half = 2.0 * std::sqrt(std::max(f.moment_major_var_px2, 0.0)) +
                      4.0 * std::sqrt(blur_var_px2) + 2.0;
  const cv::Rect box(cvRound(f.ellipse_moments.center_px.x - half),
                     cvRound(f.ellipse_moments.center_px.y - half), cvRound(2 * half) + 1,
                     cvRound(2 * half) + 1);
  const cv::Rect inside = box & cv::Rect(0, 0, image.cols, image.rows);
  *origin = inside.tl();
  const double scale = 1.0 / ((1 << bit_depth) - 1);
  std::vector<Pixel> out;
  for (int row = inside.y; row < inside.br().y; ++row) {
    for (int col = inside.x; col < inside.br().x; ++col) {
      out.push_back({static_cast<double>(col - origin->x), static_cast<double>(row - origin->y),
                     image.at<std::uint16_t>(row, col) * scale});
    }
  }
  return out;
}

// The noise variance of each pixel: read (the background's) + k x signal, k regressed (through
// the origin, on the signal above background) from the squared residuals of the previous pass.
std::vector<double> NoiseVariances(const std::vector<Pixel>& pixels, const WindowResiduals& model,
                                   const double* v, double read_var) {
  const std::vector<double>& mean = model.MeansAt(v);
  std::vector<double> signal(pixels.size());
  double sxy = 0.0, sxx = 0.0;
  for (size_t i = 0; i < pixels.size(); ++i) {
    const double r = v[6] + v[5] * mean[i] - pixels[i].value;
    signal[i] = std::max(0.0, r + pixels[i].value - v[6]);
    sxy += signal[i] * (r * r - read_var);
    sxx += signal[i] * signal[i];
  }
  const double k = sxx > 0.0 ? std::max(0.0, sxy / sxx) : 0.0;
  std::vector<double> var(pixels.size());
  for (size_t i = 0; i < pixels.size(); ++i) var[i] = read_var + k * signal[i];
  return var;
}

// The noise of P's anisotropy a = ((P11 - P22) / 2, P12) at the solution: E |a_noise|^2 =
// var a1 + var a2 from the parameters' covariance, the inverse Fisher information (J^T J)^-1 of
// the weighted residuals (what ceres::Covariance computes, without its sparse machinery: 7
// parameters; J^T J's eigen-decomposition). NaN when J^T J is singular to Ceres's own threshold
// (reciprocal condition 1e-14).
double AnisotropyNoiseVar(const WindowResiduals& residuals, const double* v) {
  Eigen::VectorXd r(residuals.NumResiduals());
  Eigen::Matrix<double, Eigen::Dynamic, kParams> jacobian(residuals.NumResiduals(), kParams);
  residuals(v, r.data(), jacobian.data());
  const Eigen::Matrix<double, kParams, kParams> information = jacobian.transpose() * jacobian;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, kParams, kParams>> eigen(information);
  if (eigen.info() != Eigen::Success) return std::numeric_limits<double>::quiet_NaN();
  const Eigen::Matrix<double, kParams, 1> lambda = eigen.eigenvalues();  // ascending
  if (!(lambda(0) > 1e-14 * lambda(kParams - 1))) return std::numeric_limits<double>::quiet_NaN();
  const Eigen::Matrix<double, kParams, kParams> c =
      eigen.eigenvectors() * lambda.cwiseInverse().asDiagonal() * eigen.eigenvectors().transpose();
  return 0.25 * (c(2, 2) + c(4, 4) - 2.0 * c(2, 4)) + c(3, 3);
}

// One weighted least-squares pass (ceres::TinySolver) from v; returns the weighted cost per pixel.
// anisotropy_noise_var: when set, receives AnisotropyNoiseVar at the pass's solution.
double SolvePass(const WindowResiduals& residuals, double* v, bool* ok,
                 double* anisotropy_noise_var = nullptr) {
  ceres::TinySolver<WindowResiduals> solver;
  solver.options.function_tolerance = kChi2Tolerance;
  Eigen::Matrix<double, kParams, 1> x(v);
  const auto& summary = solver.Solve(residuals, &x);
  std::copy(x.data(), x.data() + kParams, v);
  *ok = std::isfinite(summary.final_cost) && v[2] > 0.0 && v[4] > 0.0 && v[2] * v[4] > v[3] * v[3];
  if (*ok && anisotropy_noise_var != nullptr) {
    *anisotropy_noise_var = AnisotropyNoiseVar(residuals, v);
  }
  return 2.0 * summary.final_cost / static_cast<double>(residuals.NumResiduals());
}

// P's eigenvalues tr/2 -+ |a|, a = ((P11 - P22) / 2, P12). The fitted |a|^2 is the true one plus
// noise of mean noise_var = E |a_noise|^2: on a round blob the larger disc variance (1/4 over the
// smaller eigenvalue) is biased up by ~0.9 noise sd and scatters more than the mean size. With
// shrink, a blob whose |a|^2 is within kCircleNoiseMultiple x noise_var is a circle (|a| = 0: both
// axes the mean size, theta 0); beyond it |a|^2 loses noise_var (its noise bias).
void DiscEigenvalues(const double* v, double noise_var, bool shrink, double* p_small,
                     double* p_large) {
  const double tr = v[2] + v[4];
  const double a2 = 0.25 * (v[2] - v[4]) * (v[2] - v[4]) + v[3] * v[3];
  const double noise = shrink && std::isfinite(noise_var) ? std::max(0.0, noise_var) : 0.0;
  const bool round = a2 < kCircleNoiseMultiple * noise;
  const double root = round ? 0.0 : std::sqrt(std::max(0.0, a2 - noise));
  *p_small = 0.5 * tr - root;
  *p_large = 0.5 * tr + root;
}

// The read-noise variance from the pixels outside the disc and its blur (median absolute
// deviation of the outermost ring of the window).
double ReadVariance(const std::vector<Pixel>& pixels, const cv::Point2d& centre, double radius) {
  std::vector<double> ring;
  for (const Pixel& p : pixels) {
    if (std::hypot(p.x - centre.x, p.y - centre.y) > radius) ring.push_back(p.value);
  }
  if (ring.size() < 16) return 0.0;
  const double sd = RobustNoiseSd(&ring);
  return sd * sd;
}

}  // namespace

double BlobEdgeValue(const double v[5], double x, double y, double edge_sd, double d[5]) {
  return PixelMean(v, x, y, edge_sd, d);
}

BlobFitResult FitBlob(const cv::Mat& image, int bit_depth, const Features& features,
                      double blur_var_px2) {
  BlobFitResult out;
  out.blur_var_px2 = blur_var_px2;
  const double gauss_var = blur_var_px2 - kPixelAreaVarPx2;
  if (!features.Usable() || !features.ellipse_moments.valid || image.type() != CV_16UC1 ||
      !(gauss_var > 0.01)) {
    return out;
  }
  const double blur_sd = std::sqrt(gauss_var);
  const double edge_sd = std::sqrt(gauss_var + kPixelSpreadVarPx2);  // PixelMean's s
  cv::Point origin;
  const std::vector<Pixel> pixels = BlobPixels(image, bit_depth, features, blur_var_px2, &origin);
  double v[kParams];
  if (!StartFromMoments(features, blur_var_px2, origin, v)) return out;
  const double reach = 2.0 * std::sqrt(features.moment_major_var_px2) + 3.0 * blur_sd;
  const double scale = 1.0 / ((1 << bit_depth) - 1);
  const double read_var = std::max(ReadVariance(pixels, {v[0], v[1]}, reach), scale * scale / 12.0);
  WindowResiduals model(pixels, edge_sd);
  model.SetVariances(std::vector<double>(pixels.size(), read_var));
  bool ok = false;
  double chi2 = 0.0;
  double noise_var = std::numeric_limits<double>::quiet_NaN();
  // IRLS, two passes: the read noise's weights, then the weights of the first pass's model (a
  // third pass, weights from the second's, moved no figure: docs/estimator.md "The blob fit").
  for (int pass = 0; pass < 2; ++pass) {
    chi2 = SolvePass(model, v, &ok, pass == 1 ? &noise_var : nullptr);
    if (!ok) return out;
    if (pass == 0) model.SetVariances(NoiseVariances(pixels, model, v, read_var));
  }
  double p_small, p_large;  // 1/A^2, 1/B^2
  DiscEigenvalues(v, noise_var, false, &p_small, &p_large);
  out.raw_major_var_px2 = 0.25 / p_small;
  out.raw_minor_var_px2 = 0.25 / p_large;
  out.anisotropy_noise_var = noise_var;
  DiscEigenvalues(v, noise_var, true, &p_small, &p_large);
  out.ok = p_small > 0.0 && out.raw_major_var_px2 > 0.0;
  out.center_px = cv::Point2d(v[0] + origin.x, v[1] + origin.y);
  out.major_var_px2 = 0.25 / p_small;
  out.minor_var_px2 = 0.25 / p_large;
  // The major axis is the eigenvector of P's smaller eigenvalue.
  out.angle_deg = 0.5 * std::atan2(-2.0 * v[3], v[4] - v[2]) * 180.0 / kPi;
  out.chi2_per_pixel = chi2;
  out.pixels = static_cast<int>(pixels.size());
  return out;
}

bool RefineWithBlobFit(const cv::Mat& image, int bit_depth, const CalibrationModel& model,
                       Features* features) {
  const GeometricModel& g = model.geometric;
  if (!g.fitted() || !features->Usable()) return false;
  const double d_mm = g.DistanceMm(features->moment_major_var_px2);
  if (!std::isfinite(d_mm) || d_mm <= 0.0) return false;
  const double blur = g.BlurVarPx2(d_mm);
  const BlobFitResult fit = FitBlob(image, bit_depth, *features, blur);
  if (!fit.ok) return false;
  features->moment_major_var_px2 = fit.major_var_px2 + blur;
  features->moment_minor_var_px2 = fit.minor_var_px2 + blur;
  return true;
}

}  // namespace irdist
