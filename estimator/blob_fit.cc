#include "estimator/blob_fit.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include <ceres/ceres.h>

namespace irdist {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kPixelAreaVarPx2 = 1.0 / 12.0;
// Parameters: centre x, y (relative to the fit's origin), P11, P12, P22, amplitude, background.
constexpr int kParams = 7;
// A round blob's fitted |a|^2 (anisotropy, below) is exponential with mean E |a_noise|^2: it
// exceeds 4x that mean in e^-4 = 1.8% of frames. Below it the blob is taken as a circle; above,
// only the noise's mean is removed, so a clearly elliptical blob keeps its axes (unbiased |a|^2).
// A soft shrink (|a|^2 less 3x the noise) reached the same dispersion at theta 0 but shortened |a|
// at 10-20 deg (theta max on Fig. 13 0.431 -> 0.444 deg); subtracting 1x alone removes the bias
// but not the scatter (docs/estimator.md).
constexpr double kCircleNoiseMultiple = 4.0;

// The blurred disc's value at a point, relative to its amplitude: Phi of the signed distance to the
// edge (to first order in the quadratic form, exact on a circle), shifted inward by the edge's
// curvature kappa s^2 / 2 (the blurred edge of a disc of radius R sits s^2 / (2R) inside it).
template <typename T>
T DiscValue(const T* v, double x, double y, double s) {
  const T dx = x - v[0], dy = y - v[1];
  const T q = v[2] * dx * dx + 2.0 * v[3] * dx * dy + v[4] * dy * dy;
  if (q < T(0.09)) return T(1.0);  // well inside: the blur (< 0.3 of the size) does not reach
  const T root_q = sqrt(q);
  const T gx = v[2] * dx + v[3] * dy, gy = v[3] * dx + v[4] * dy;
  const T n2 = gx * gx + gy * gy;
  const T n = sqrt(n2);
  const T dist = (1.0 - root_q) * root_q / n;
  const T gpg = v[2] * gx * gx + 2.0 * v[3] * gx * gy + v[4] * gy * gy;
  const T kappa = (n2 * (v[2] + v[4]) - gpg) / (n2 * n);
  const T z = (dist - 0.5 * kappa * s * s) / s;
  return 0.5 * erfc(-z * 0.70710678118654752440);
}

double ValueOf(double x) { return x; }
template <typename T, int N>
double ValueOf(const ceres::Jet<T, N>& x) {
  return x.a;
}

// Where the pixel at (x, y) lies against the blurred edge, from the current parameters: +1 when
// all of it is so far inside that the disc's value is 1 to 1e-12, -1 when so far outside that it
// is 0, else 0 (the pixel must be integrated). The margin covers the sub-samples' reach (0.53 px)
// and the first-order distance.
template <typename T>
int PixelSide(const T* v, double x, double y, double s) {
  double p[5];
  for (int i = 0; i < 5; ++i) p[i] = ValueOf(v[i]);
  const double dx = x - p[0], dy = y - p[1];
  const double q = p[2] * dx * dx + 2.0 * p[3] * dx * dy + p[4] * dy * dy;
  const double gx = p[2] * dx + p[3] * dy, gy = p[3] * dx + p[4] * dy;
  const double n = std::sqrt(gx * gx + gy * gy);
  if (!(q > 0.0) || !(n > 0.0)) return 0;
  const double dist = (1.0 - std::sqrt(q)) * std::sqrt(q) / n;
  const double margin = 1.0 + 8.0 * s;
  if (dist > margin) return 1;
  if (dist < -margin) return -1;
  return 0;
}

// One pixel's residual, divided by its noise sd: the model integrated on 4x4 sub-samples (a pixel
// far from the edge, PixelSide, is 1 or 0 throughout and needs none).
struct PixelResidual {
  double x, y, value, inv_sd, blur_sd;
  template <typename T>
  bool operator()(const T* v, T* residual) const {
    const int side = PixelSide(v, x, y, blur_sd);
    if (side != 0) {
      residual[0] = (v[6] + (side > 0 ? v[5] : T(0.0)) - value) * inv_sd;
      return true;
    }
    constexpr double kOffsets[4] = {-0.375, -0.125, 0.125, 0.375};
    T sum(0.0);
    for (double oy : kOffsets) {
      for (double ox : kOffsets) sum += DiscValue(v, x + ox, y + oy, blur_sd);
    }
    residual[0] = (v[6] + v[5] * sum / 16.0 - value) * inv_sd;
    return true;
  }
};

struct Pixel {
  double x, y, value;
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
std::vector<double> NoiseVariances(const std::vector<Pixel>& pixels, const double* v,
                                   double blur_sd, double read_var) {
  std::vector<double> signal(pixels.size());
  double sxy = 0.0, sxx = 0.0;
  for (size_t i = 0; i < pixels.size(); ++i) {
    double r = 0.0;
    PixelResidual{pixels[i].x, pixels[i].y, pixels[i].value, 1.0, blur_sd}(v, &r);
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
// var a1 + var a2 from the parameters' covariance (ceres::Covariance, the inverse Fisher
// information of the weighted residuals). NaN when the covariance cannot be computed.
double AnisotropyNoiseVar(ceres::Problem* problem, const double* v) {
  ceres::Covariance::Options options;
  options.algorithm_type = ceres::DENSE_SVD;
  options.num_threads = 1;
  ceres::Covariance covariance(options);
  const std::vector<std::pair<const double*, const double*>> blocks = {{v, v}};
  if (!covariance.Compute(blocks, problem)) return std::numeric_limits<double>::quiet_NaN();
  double c[kParams * kParams];
  if (!covariance.GetCovarianceBlock(v, v, c)) return std::numeric_limits<double>::quiet_NaN();
  const auto at = [&c](int i, int j) { return c[i * kParams + j]; };
  return 0.25 * (at(2, 2) + at(4, 4) - 2.0 * at(2, 4)) + at(3, 3);
}

// One weighted least-squares pass (Ceres, dense QR) from v; returns the weighted cost per pixel.
// anisotropy_noise_var: when set, receives AnisotropyNoiseVar at the pass's solution.
double SolvePass(const std::vector<Pixel>& pixels, const std::vector<double>& var, double blur_sd,
                 double* v, bool* ok, double* anisotropy_noise_var = nullptr) {
  ceres::Problem problem;
  for (size_t i = 0; i < pixels.size(); ++i) {
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<PixelResidual, 1, kParams>(
                                 new PixelResidual{pixels[i].x, pixels[i].y, pixels[i].value,
                                                   1.0 / std::sqrt(var[i]), blur_sd}),
                             nullptr, v);
  }
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  options.max_num_iterations = 50;
  options.num_threads = 1;
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  *ok = summary.IsSolutionUsable() && v[2] > 0.0 && v[4] > 0.0 && v[2] * v[4] > v[3] * v[3];
  if (*ok && anisotropy_noise_var != nullptr) {
    *anisotropy_noise_var = AnisotropyNoiseVar(&problem, v);
  }
  return 2.0 * summary.final_cost / static_cast<double>(pixels.size());
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
  auto mid = ring.begin() + ring.size() / 2;
  std::nth_element(ring.begin(), mid, ring.end());
  const double median = *mid;
  for (double& x : ring) x = std::abs(x - median);
  std::nth_element(ring.begin(), mid, ring.end());
  const double sd = 1.4826 * *mid;
  return sd * sd;
}

}  // namespace

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
  cv::Point origin;
  const std::vector<Pixel> pixels = BlobPixels(image, bit_depth, features, blur_var_px2, &origin);
  double v[kParams];
  if (!StartFromMoments(features, blur_var_px2, origin, v)) return out;
  const double reach = 2.0 * std::sqrt(features.moment_major_var_px2) + 3.0 * blur_sd;
  const double scale = 1.0 / ((1 << bit_depth) - 1);
  const double read_var = std::max(ReadVariance(pixels, {v[0], v[1]}, reach), scale * scale / 12.0);
  std::vector<double> var(pixels.size(), read_var);
  bool ok = false;
  double chi2 = 0.0;
  double noise_var = std::numeric_limits<double>::quiet_NaN();
  for (int pass = 0; pass < 3; ++pass) {  // IRLS: weights from the previous pass's model
    chi2 = SolvePass(pixels, var, blur_sd, v, &ok, pass == 2 ? &noise_var : nullptr);
    if (!ok) return out;
    if (pass < 2) var = NoiseVariances(pixels, v, blur_sd, read_var);
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
