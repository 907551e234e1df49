#include "estimator/blob_fit.h"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "base/pi.h"
#include "estimator/blob_fit_errors.h"
#include "estimator/blob_pixel_model.h"
#include "estimator/normal_lm.h"
#include "estimator/psf_anisotropy.h"

namespace irdist {
namespace {

// A pass stops when a step changes the chi^2 by less than this, or when the next Gauss-Newton
// step would (its Newton decrement, estimator/normal_lm.h: one model evaluation fewer a pass, 4
// instead of 6 a fit on bench_estimator's blob): a parameter is then within about 1% of its
// standard error of the minimum (both tolerances absolute, in |f|^2 units).
constexpr double kChi2Tolerance = 1e-4;
// A pass whose solution only sets the next pass's weights (and the profiles' one pass, whose
// joint Gauss-Newton step corrects the rest) stops sooner: the weights are the model's shape,
// which a step changing the chi^2 by this little moves by a small fraction of a noise sd, and the
// last pass converges to its tolerance whatever its start.
constexpr double kWeightsPassTolerance = 0.5;
// The last pass takes its last Gauss-Newton step unevaluated when the step's predicted decrease
// of the chi^2 (the Newton decrement) is below this: a step under three standard errors
// (Mahalanobis). On bench_estimator's blob the new weights' step is 1.8 standard errors and lands
// within 0.009 of one from the minimum (the decrement after it 7.5e-5); the model's curvature
// puts a 3 se step within 0.03 se.
constexpr double kFinalStepDecrement = 9.0;
// The solution's weights: the frame's shot noise over a floor of this share of the amplitude, the
// model's own shape (ShapeVariances), not the frame's noise regressed from its residuals, which
// made the size follow the frame's noise and amplitude wherever the lens is not the model's. The
// share trades efficiency (the size's scatter 2% above a floor at the shot noise's own, 0.01-0.03)
// against the tails' misfit (docs/estimator.md "The blob fit's weights", the figures).
constexpr double kShapeReadShare = 0.1;
// Parameters: centre x, y (relative to the fit's origin), P11, P12, P22, amplitude, background.
constexpr int kParams = 7;

struct Pixel {
  double x, y, value;
};

using blob_model::MakeResponse;
using blob_model::PixelResponse;
using blob_model::Spread;
using blob_model::SquareMean;

// `out` (size x size) symmetric, from its upper triangle `upper` stored by rows.
template <typename Matrix>
void SymmetricFromUpper(const double* upper, int size, Matrix* out) {
  for (int k = 0; k < size; ++k) {
    for (int l = k; l < size; ++l) (*out)(k, l) = (*out)(l, k) = upper[k * size + l];
  }
}

// Every pixel's residual, divided by its noise sd, and the analytic Jacobian, summed into the
// normal equations J^T J and J^T r for the solver (estimator/normal_lm.h, TinySolver's steps): no
// n x 7 Jacobian is written. The model (each pixel's mean and its derivatives) is computed once
// per point and kept; the weights are applied as it is read. So the normal equations at an
// accepted trial step, the next pass's start (new weights, same point), the noise regression and
// the covariance at a pass's solution cost no evaluation of the model. A pixel whose derivatives
// are all zero (flat: wholly inside or outside the disc's edge band) adds to the amplitude's and
// background's terms only.
class WindowResiduals : public NormalProblem<kParams> {
 public:
  // `pixels`: the window's, row by row (cols x rows, BlobPixels).
  WindowResiduals(const std::vector<Pixel>& pixels, int cols, int rows, PixelResponse response)
      : pixels_(pixels), cols_(cols), rows_(rows), response_(std::move(response)),
        inv_sd_(pixels.size()), mean_(pixels.size()), d_mean_(pixels.size() * 5) {}
  // Each pixel's noise variance (the residuals' weights, 1 / sd).
  void SetVariances(const std::vector<double>& var) {
    for (size_t i = 0; i < var.size(); ++i) inv_sd_[i] = 1.0 / std::sqrt(var[i]);
  }
  int NumResiduals() const { return static_cast<int>(pixels_.size()); }
  bool Evaluate(const double* v, bool want_normal,
                NormalEquations<kParams>* normal) const override {
    const std::vector<double>& mean = MeansAt(v);
    const size_t n = pixels_.size();
    double cost2 = 0.0;
    if (!want_normal) {
      for (size_t i = 0; i < n; ++i) {
        const double r = Residual(v, mean, i) * inv_sd_[i];
        cost2 += r * r;
      }
      normal->cost2 = cost2;
      return std::isfinite(cost2);
    }
    // The upper triangle of J^T J by rows (k <= l) and J^T r; the flat pixels' sums apart.
    double jtj[kParams * kParams] = {}, jtr[kParams] = {};
    double flat_mm = 0.0, flat_m = 0.0, flat_1 = 0.0, flat_mr = 0.0, flat_r = 0.0;
    double j[kParams];
    for (size_t i = 0; i < n; ++i) {
      const double s = inv_sd_[i];
      const double r = Residual(v, mean, i) * s;
      cost2 += r * r;
      const double* d = &d_mean_[i];
      if (d[0] == 0.0 && d[n] == 0.0 && d[2 * n] == 0.0 && d[3 * n] == 0.0 && d[4 * n] == 0.0) {
        const double ms = mean[i] * s;
        flat_mm += ms * ms, flat_m += ms * s, flat_1 += s * s, flat_mr += ms * r, flat_r += s * r;
        continue;
      }
      JacobianRow(v, mean, i, s, j);
      for (int k = 0; k < kParams; ++k) {
        jtr[k] += j[k] * r;
        for (int l = k; l < kParams; ++l) jtj[k * kParams + l] += j[k] * j[l];
      }
    }
    jtj[5 * kParams + 5] += flat_mm, jtj[5 * kParams + 6] += flat_m, jtj[6 * kParams + 6] += flat_1;
    jtr[5] += flat_mr, jtr[6] += flat_r;
    for (int k = 0; k < kParams; ++k) normal->jtr(k) = jtr[k];
    SymmetricFromUpper(jtj, kParams, &normal->jtj);
    normal->cost2 = cost2;
    return std::isfinite(cost2);
  }
  // At v, in one pass over the pixels: J^T W J in the model's weights W (*h), J^T W Sigma W J for
  // the noise variances `var` (Sigma, *m), and the residuals' chi-square in Sigma's weights.
  double Sandwich(const double* v, const std::vector<double>& var,
                  Eigen::Matrix<double, kParams, kParams>* h,
                  Eigen::Matrix<double, kParams, kParams>* m) const {
    const std::vector<double>& mean = MeansAt(v);
    const size_t n = pixels_.size();
    double a[kParams * kParams] = {}, b[kParams * kParams] = {}, j[kParams];
    double chi2 = 0.0;
    for (size_t i = 0; i < n; ++i) {
      const double r = Residual(v, mean, i);
      chi2 += r * r / var[i];
      const double w = inv_sd_[i] * inv_sd_[i], spread = w * w * var[i];
      JacobianRow(v, mean, i, 1.0, j);
      for (int k = 0; k < kParams; ++k) {
        for (int l = k; l < kParams; ++l) {
          a[k * kParams + l] += w * j[k] * j[l];
          b[k * kParams + l] += spread * j[k] * j[l];
        }
      }
    }
    SymmetricFromUpper(a, kParams, h);
    SymmetricFromUpper(b, kParams, m);
    return chi2;
  }
  // Each pixel's model mean (relative to the amplitude) at v; nothing is computed when v is the
  // last point.
  const std::vector<double>& MeansAt(const double* v) const {
    if (!computed_ || !std::equal(v, v + kParams, at_)) Compute(v);
    return mean_;
  }
  // Pixel i's residual at v, unweighted (the model less the gray level); mean: MeansAt(v).
  double Residual(const double* v, const std::vector<double>& mean, size_t i) const {
    return v[6] + v[5] * mean[i] - pixels_[i].value;
  }

  // The Gauss-Newton system at v with E more parameters after the seven (the blur, the crosstalk's
  // variance): J^T J and J^T r, each one's column by a forward difference of the model to
  // `shifted[e]` (the same pixels and weights with that parameter `steps[e]` larger).
  template <int E>
  void ExtendedSystem(const double* v, const std::array<const WindowResiduals*, E>& shifted,
                      const std::array<double, E>& steps,
                      Eigen::Matrix<double, kParams + E, kParams + E>* jtj,
                      Eigen::Matrix<double, kParams + E, 1>* jtr) const {
    std::array<const std::vector<double>*, E> up;
    for (int e = 0; e < E; ++e) up[e] = &shifted[e]->MeansAt(v);
    const std::vector<double>& mean = MeansAt(v);
    const size_t n = pixels_.size();
    constexpr int m = kParams + E;
    double a[m * m] = {}, b[m] = {}, j[m];
    for (size_t i = 0; i < n; ++i) {
      const double s = inv_sd_[i];
      const double r = Residual(v, mean, i) * s;
      JacobianRow(v, mean, i, s, j);
      for (int e = 0; e < E; ++e) j[kParams + e] = v[5] * s * ((*up[e])[i] - mean[i]) / steps[e];
      for (int k = 0; k < m; ++k) {
        b[k] += j[k] * r;
        for (int l = k; l < m; ++l) a[k * m + l] += j[k] * j[l];
      }
    }
    for (int k = 0; k < m; ++k) (*jtr)(k) = b[k];
    SymmetricFromUpper(a, m, jtj);
  }

 private:
  // Pixel i's row of the Jacobian at v (the disc's five, the amplitude, the background), scaled
  // by s (its weight, 1 / sd); mean: MeansAt(v).
  void JacobianRow(const double* v, const std::vector<double>& mean, size_t i, double s,
                   double* j) const {
    const size_t n = pixels_.size();
    const double amplitude_s = v[5] * s;
    for (int k = 0; k < 5; ++k) j[k] = amplitude_s * d_mean_[k * n + i];
    j[5] = mean[i] * s;
    j[6] = s;
  }
  // The model on the window grown by the crosstalk's reach (planes: the mean, then its five
  // derivatives), each pixel's square integrated, then spread by the crosstalk onto the window.
  // Without crosstalk the grid is the window and the planes are mean_ and d_mean_ themselves.
  void Compute(const double* v) const {
    const int reach = response_.reach;
    const int cols = cols_ + 2 * reach, rows = rows_ + 2 * reach;
    const size_t grid = static_cast<size_t>(cols) * rows;
    if (reach > 0) grown_.resize(6 * grid);
    double* mean = reach > 0 ? grown_.data() : mean_.data();
    double* d_mean = reach > 0 ? grown_.data() + grid : d_mean_.data();
    double d[5];
    for (int row = 0; row < rows; ++row) {
      for (int col = 0; col < cols; ++col) {
        const size_t i = static_cast<size_t>(row) * cols + col;
        mean[i] = SquareMean(v, col - reach, row - reach, response_, d);
        for (int k = 0; k < 5; ++k) d_mean[k * grid + i] = d[k];
      }
    }
    const size_t n = pixels_.size();
    for (int p = 0; reach > 0 && p < 6; ++p) {
      Spread(grown_.data() + p * grid, rows, cols, response_.kernel, &across_,
             p == 0 ? mean_.data() : d_mean_.data() + (p - 1) * n);
    }
    std::copy(v, v + kParams, at_);
    computed_ = true;
  }

  const std::vector<Pixel>& pixels_;
  int cols_, rows_;
  PixelResponse response_;
  std::vector<double> inv_sd_;
  // The last point computed and its model (the solver holds the problem const).
  mutable std::vector<double> mean_, d_mean_;
  mutable std::vector<double> grown_;   // with crosstalk: the planes on the window grown by reach
  mutable std::vector<double> across_;  // with crosstalk: a plane spread along x
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
                              double blur_var_px2, cv::Rect* window) {
  const double half = 2.0 * std::sqrt(std::max(f.moment_major_var_px2, 0.0)) +
                      4.0 * std::sqrt(blur_var_px2) + 2.0;
  const cv::Rect box(cvRound(f.ellipse_moments.center_px.x - half),
                     cvRound(f.ellipse_moments.center_px.y - half), cvRound(2 * half) + 1,
                     cvRound(2 * half) + 1);
  const cv::Rect inside = box & cv::Rect(0, 0, image.cols, image.rows);
  *window = inside;
  const double scale = 1.0 / ((1 << bit_depth) - 1);
  std::vector<Pixel> out;
  for (int row = inside.y; row < inside.br().y; ++row) {
    for (int col = inside.x; col < inside.br().x; ++col) {
      out.push_back({static_cast<double>(col - inside.x), static_cast<double>(row - inside.y),
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
    const double r = model.Residual(v, mean, i);
    signal[i] = std::max(0.0, r + pixels[i].value - v[6]);
    sxy += signal[i] * (r * r - read_var);
    sxx += signal[i] * signal[i];
  }
  const double k = sxx > 0.0 ? std::max(0.0, sxy / sxx) : 0.0;
  std::vector<double> var(pixels.size());
  for (size_t i = 0; i < pixels.size(); ++i) var[i] = read_var + k * signal[i];
  return var;
}

// The second pass's weights: var = read (1 + shape / kShapeReadShare), shape the model's signal
// over its amplitude (0..1): the same weights whatever the frame's amplitude and noise (the scale,
// the read noise's variance where the signal is 0, sets only the pass's tolerance).
std::vector<double> ShapeVariances(const WindowResiduals& model, const double* v, double read_var) {
  const std::vector<double>& mean = model.MeansAt(v);
  std::vector<double> var(mean.size());
  for (size_t i = 0; i < mean.size(); ++i) {
    var[i] = read_var * (1.0 + std::max(0.0, mean[i]) / kShapeReadShare);
  }
  return var;
}

using Covariance = BlobCovariance;
static_assert(kParams == BlobCovariance::RowsAtCompileTime, "the covariance's parameters");

// The covariance of the solution at `at` in the model's weights W (ShapeVariances) under the
// frame's own noise (NoiseVariances: read + k x signal, Sigma): the least squares' sandwich
// H^-1 M H^-1, H = J^T W J, M = J^T W Sigma W J (as ceres::Covariance, without its sparse
// machinery: H's eigen-decomposition); false when H is singular to Ceres's own threshold
// (reciprocal condition 1e-14). *chi2_per_pixel: the residuals' chi-square per pixel in Sigma's
// weights (~1 when the model fits).
bool NoiseCovariance(const WindowResiduals& model, const std::vector<Pixel>& pixels,
                     const double* at, double read_var, Covariance* c, double* chi2_per_pixel) {
  Covariance h, m;
  const std::vector<double> var = NoiseVariances(pixels, model, at, read_var);
  *chi2_per_pixel = model.Sandwich(at, var, &h, &m) / static_cast<double>(pixels.size());
  const Eigen::SelfAdjointEigenSolver<Covariance> eigen(h);
  if (eigen.info() != Eigen::Success) return false;
  const Eigen::Matrix<double, kParams, 1> lambda = eigen.eigenvalues();  // ascending
  if (!(lambda(0) > 1e-14 * lambda(kParams - 1))) return false;
  const Covariance h_inverse =
      eigen.eigenvectors() * lambda.cwiseInverse().asDiagonal() * eigen.eigenvectors().transpose();
  *c = h_inverse * m * h_inverse;
  return true;
}

// One least-squares pass (ceres::TinySolver) from v in the model's weights; returns the weighted
// cost per pixel. evaluated: when set, the pass ends with a step within kFinalStepDecrement of
// the minimum taken without evaluating the model there (estimator/normal_lm.h
// final_step_decrement: one model evaluation of three a fit, the same solution), and receives the
// point before it, whose model is the last one computed (NoiseCovariance's point).
double SolvePass(const WindowResiduals& residuals, double* v, bool* ok,
                 Eigen::Matrix<double, kParams, 1>* evaluated = nullptr,
                 double tolerance = kChi2Tolerance) {
  NormalLmOptions options;
  options.function_tolerance = tolerance;
  options.decrement_tolerance = tolerance;
  if (evaluated != nullptr) options.final_step_decrement = kFinalStepDecrement;
  Eigen::Matrix<double, kParams, 1> x(v), last;
  const NormalLmSummary summary = SolveNormalLm(residuals, options, &x, &last);
  std::copy(x.data(), x.data() + kParams, v);
  if (evaluated != nullptr) *evaluated = last;
  *ok = std::isfinite(summary.final_cost) && v[2] > 0.0 && v[4] > 0.0 && v[2] * v[4] > v[3] * v[3];
  return 2.0 * summary.final_cost / static_cast<double>(residuals.NumResiduals());
}

// P's eigenvalues tr/2 -+ |a|, a = ((P11 - P22) / 2, P12). The fitted |a|^2 is the true one plus
// noise of mean noise_var = E |a_noise|^2: on a round blob the larger disc variance (1/4 over the
// smaller eigenvalue) is biased up by ~0.9 noise sd and scatters more than the mean size. With
// shrink, |a|^2 by the continuous round-blob rule (psf_anisotropy.h DenoisedAnisotropy2): ~0 for a
// round blob's noise, |a|^2 less its noise bias for a clearly elliptical one, no step between
// (the hard step at 4x the noise turned a rare false alarm into a 4 deg outlier at theta 0).
void DiscEigenvalues(const double* v, double noise_var, bool shrink, double* p_small,
                     double* p_large) {
  const double tr = v[2] + v[4];
  const double a2 = 0.25 * (v[2] - v[4]) * (v[2] - v[4]) + v[3] * v[3];
  const double root = std::sqrt(std::max(0.0, shrink ? DenoisedAnisotropy2(a2, noise_var) : a2));
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

// The window around the blob, the fit's start in it and the read noise FitBlobPasses and
// ProfileBlobBlur share; false when the frame cannot be fitted at this blur.
struct WindowStart {
  std::vector<Pixel> pixels;
  cv::Rect window;
  double v[kParams] = {};
  double read_var = 0.0;
  Crosstalk crosstalk;  // the crosstalk as used (the optics keep kMinOpticsVarPx2)
};
bool StartWindow(const cv::Mat& image, int bit_depth, const Features& features,
                 double blur_var_px2, const Crosstalk& crosstalk, WindowStart* s) {
  const double gauss_var = blur_var_px2 - kPixelAreaVarPx2;
  if (!features.Usable() || !features.ellipse_moments.valid || image.type() != CV_16UC1 ||
      !(gauss_var > kMinOpticsVarPx2) || !(crosstalk.var_px2 >= 0.0)) {
    return false;
  }
  s->crosstalk = RoomFor(crosstalk, blur_var_px2);
  s->pixels = BlobPixels(image, bit_depth, features, blur_var_px2, &s->window);
  if (!StartFromMoments(features, blur_var_px2, s->window.tl(), s->v)) return false;
  const double reach = 2.0 * std::sqrt(features.moment_major_var_px2) + 3.0 * std::sqrt(gauss_var);
  const double scale = 1.0 / ((1 << bit_depth) - 1);
  s->read_var =
      std::max(ReadVariance(s->pixels, {s->v[0], s->v[1]}, reach), scale * scale / 12.0);
  return true;
}

// The window's model at `blur_var_px2`, weighted by the read noise.
WindowResiduals ModelOf(const WindowStart& s, double blur_var_px2, const Crosstalk& crosstalk,
                        const PsfAnisotropy& psf) {
  WindowResiduals model(s.pixels, s.window.width, s.window.height,
                        ResponseOf(blur_var_px2, crosstalk, psf));
  model.SetVariances(std::vector<double>(s.pixels.size(), s.read_var));
  return model;
}

}  // namespace

// FitBlob with `passes` passes (1: the read noise's weights alone, for FitBlurSplit; 2: then the
// weights of the first pass's shape, and the errors).
BlobFitResult FitBlobPasses(const cv::Mat& image, int bit_depth, const Features& features,
                            double blur_var_px2, const Crosstalk& crosstalk, int passes,
                            const PsfAnisotropy& psf) {
  BlobFitResult out;
  out.blur_var_px2 = blur_var_px2;
  WindowStart s;
  if (!StartWindow(image, bit_depth, features, blur_var_px2, crosstalk, &s)) return out;
  out.crosstalk_var_px2 = s.crosstalk.var_px2;
  const std::vector<Pixel>& pixels = s.pixels;
  const cv::Rect& window = s.window;
  double* v = s.v;
  WindowResiduals model = ModelOf(s, blur_var_px2, s.crosstalk, psf);
  bool ok = false, covariance_ok = false;
  Eigen::Matrix<double, kParams, 1> evaluated;
  double chi2 =
      SolvePass(model, v, &ok, nullptr, passes > 1 ? kWeightsPassTolerance : kChi2Tolerance);
  if (!ok) return out;
  out.read_weighted_chi2 = chi2;
  Covariance covariance;
  if (passes > 1) {
    const std::vector<double> weights_var = ShapeVariances(model, v, s.read_var);
    model.SetVariances(weights_var);
    chi2 = SolvePass(model, v, &ok, &evaluated);
    if (!ok) return out;
    covariance_ok =
        NoiseCovariance(model, pixels, evaluated.data(), s.read_var, &covariance, &chi2);
  }
  const double noise_var =
      covariance_ok ? AnisotropyNoiseVar(covariance) : std::numeric_limits<double>::quiet_NaN();
  double p_small, p_large;  // 1/A^2, 1/B^2
  DiscEigenvalues(v, noise_var, false, &p_small, &p_large);
  out.raw_major_var_px2 = 0.25 / p_small;
  out.raw_minor_var_px2 = 0.25 / p_large;
  out.anisotropy_noise_var = noise_var;
  DiscEigenvalues(v, noise_var, true, &p_small, &p_large);
  out.ok = p_small > 0.0 && out.raw_major_var_px2 > 0.0;
  if (covariance_ok && out.ok) {
    TraceSize(covariance, v, chi2, &out.trace_var_px2, &out.trace_var_se_px2);
    out.major_var_se_px2 = MajorVarSe(covariance, v, noise_var, p_small, chi2);
  }
  out.center_px = cv::Point2d(v[0] + window.x, v[1] + window.y);
  out.major_var_px2 = 0.25 / p_small;
  out.minor_var_px2 = 0.25 / p_large;
  // The major axis is the eigenvector of P's smaller eigenvalue.
  out.angle_deg = 0.5 * std::atan2(-2.0 * v[3], v[4] - v[2]) * 180.0 / kPi;
  out.chi2_per_pixel = chi2;
  out.amplitude = v[5], out.background = v[6];
  out.pixels = static_cast<int>(pixels.size());
  return out;
}

BlobBlurProfile ProfileBlobBlur(const cv::Mat& image, int bit_depth, const Features& features,
                                double blur_var_px2, const Crosstalk& crosstalk,
                                const PsfAnisotropy& psf) {
  BlobBlurProfile out;
  WindowStart s;
  if (!StartWindow(image, bit_depth, features, blur_var_px2, crosstalk, &s)) return out;
  WindowResiduals model = ModelOf(s, blur_var_px2, s.crosstalk, psf);
  // The fit to the weights pass's tolerance: the joint Gauss-Newton step below corrects the
  // seven parameters' rest of the way with the blur's (the same step to 1e-5 px^2 on
  // tests/estimator/refocus's frames, a fifth less CPU).
  bool ok = false;
  out.per_pixel = SolvePass(model, s.v, &ok, nullptr, kWeightsPassTolerance);
  if (!ok) return out;
  // The step: small against the blur (the model's change in it is smooth: the forward
  // difference's error ~ step / blur), large against the normal table's 2e-10.
  const double step_px2 = 1e-3 * blur_var_px2;
  const double shifted_px2 = blur_var_px2 + step_px2;  // below the kink the crosstalk's (RoomFor)
  const WindowResiduals shifted = ModelOf(s, shifted_px2, RoomFor(crosstalk, shifted_px2), psf);
  Eigen::Matrix<double, kParams + 1, kParams + 1> jtj;
  Eigen::Matrix<double, kParams + 1, 1> jtr;
  model.ExtendedSystem<1>(s.v, {&shifted}, {step_px2}, &jtj, &jtr);
  const Eigen::LDLT<Covariance> fit(jtj.topLeftCorner<kParams, kParams>());
  if (fit.info() != Eigen::Success) return out;
  const Eigen::Matrix<double, kParams, 1> c = jtj.block<kParams, 1>(0, kParams);
  const Eigen::Matrix<double, kParams, 1> turn = fit.solve(c);  // -dv/db
  const double curvature = jtj(kParams, kParams) - c.dot(turn);
  const double gradient = jtr(kParams) - turn.dot(jtr.head<kParams>());
  if (!(curvature > 0.0) || !std::isfinite(gradient) || !(out.per_pixel > 0.0)) return out;
  out.step_px2 = -gradient / curvature;
  out.se_px2 = std::sqrt(out.per_pixel / curvature);
  // The disc's variances along dv/db, by a central difference.
  const double h = 1e-3;
  double up[kParams], down[kParams], p_small, p_large;
  for (int k = 0; k < kParams; ++k) up[k] = s.v[k] - h * turn(k), down[k] = s.v[k] + h * turn(k);
  DiscEigenvalues(up, 0.0, false, &p_small, &p_large);
  const double major_up = 0.25 / p_small, minor_up = 0.25 / p_large;
  DiscEigenvalues(down, 0.0, false, &p_small, &p_large);
  out.major_slope = (major_up - 0.25 / p_small) / (2.0 * h);
  out.minor_slope = (minor_up - 0.25 / p_large) / (2.0 * h);
  out.ok = std::isfinite(out.major_slope) && std::isfinite(out.minor_slope);
  return out;
}

BlobSplitProfile ProfileBlobSplit(const cv::Mat& image, int bit_depth, const Features& features,
                                  double blur_var_px2, const Crosstalk& crosstalk) {
  BlobSplitProfile out;
  WindowStart s;
  if (!StartWindow(image, bit_depth, features, blur_var_px2, crosstalk, &s)) return out;
  const PsfAnisotropy round;
  WindowResiduals model = ModelOf(s, blur_var_px2, s.crosstalk, round);
  bool ok = false;
  out.cost = SolvePass(model, s.v, &ok, nullptr, kWeightsPassTolerance) *
             static_cast<double>(s.pixels.size());
  if (!ok) return out;
  // Forward differences as ProfileBlobBlur's; the crosstalk's backward where the optics are at
  // their floor.
  const double blur_step = 1e-3 * blur_var_px2;
  const double room = CrosstalkRoomPx2(blur_var_px2) - s.crosstalk.var_px2;
  const double crosstalk_step = room > blur_step ? blur_step : -blur_step;
  const WindowResiduals blurrier = ModelOf(s, blur_var_px2 + blur_step, s.crosstalk, round);
  Crosstalk wider = s.crosstalk;
  wider.var_px2 += crosstalk_step;
  const WindowResiduals spread = ModelOf(s, blur_var_px2, wider, round);
  Eigen::Matrix<double, kParams + 2, kParams + 2> jtj;
  Eigen::Matrix<double, kParams + 2, 1> jtr;
  model.ExtendedSystem<2>(s.v, {&blurrier, &spread}, {blur_step, crosstalk_step}, &jtj, &jtr);
  const Eigen::LDLT<Covariance> fit(jtj.topLeftCorner<kParams, kParams>());
  if (fit.info() != Eigen::Success) return out;
  const Eigen::Matrix<double, kParams, 2> c = jtj.block<kParams, 2>(0, kParams);
  const Eigen::Matrix<double, kParams, 2> turn = fit.solve(c);
  const Eigen::Matrix2d curvature = jtj.bottomRightCorner<2, 2>() - c.transpose() * turn;
  const Eigen::Vector2d gradient = jtr.tail<2>() - turn.transpose() * jtr.head<kParams>();
  for (int a = 0; a < 2; ++a) {
    out.gradient[a] = gradient(a);
    for (int b = 0; b < 2; ++b) out.curvature[a][b] = curvature(a, b);
  }
  out.ok = gradient.allFinite() && curvature.allFinite() && curvature(0, 0) > 0.0 &&
           curvature(1, 1) > 0.0;
  return out;
}

BlobFitResult FitBlob(const cv::Mat& image, int bit_depth, const Features& features,
                      double blur_var_px2, const Crosstalk& crosstalk, const PsfAnisotropy& psf) {
  // Two passes: the read noise's weights, then the weights of the first pass's shape
  // (ShapeVariances); the errors under the frame's own noise (NoiseCovariance).
  return FitBlobPasses(image, bit_depth, features, blur_var_px2, crosstalk, 2, psf);
}

PixelResponse ResponseOf(double blur_var_px2, const Crosstalk& crosstalk,
                         const PsfAnisotropy& psf) {
  PixelResponse r = MakeResponse(blur_var_px2, crosstalk.var_px2, crosstalk.lattice_share,
                                 crosstalk.optics_excess);
  r.aniso_c = psf.c_px2, r.aniso_s = psf.s_px2;
  r.edge_correction = crosstalk.edge_correction;
  return r;
}

double BlobFitBlurVarPx2(const CalibrationModel& model, const Features& features) {
  if (!model.geometric.fitted()) return 0.0;
  const double d_mm = model.geometric.DistanceMm(features.moment_major_var_px2);
  if (!std::isfinite(d_mm) || d_mm <= 0.0) return 0.0;
  const BlurCalibration& b = model.blur_calibration;
  return b.fitted() ? b.FitBlurVarPx2(d_mm) : model.geometric.BlurVarPx2(d_mm);
}

bool RefineWithBlobFit(const cv::Mat& image, int bit_depth, const CalibrationModel& model,
                       Features* features) {
  if (!features->Usable()) return false;
  const BlurCalibration& b = model.blur_calibration;
  // The moments less the PSF's anisotropy: the fit's start and the distance of its blur.
  RemovePsfAnisotropy(b.psf_aniso_c_px2, b.psf_aniso_s_px2, features);
  const double blur = BlobFitBlurVarPx2(model, *features);
  if (!(blur > 0.0)) return false;
  const BlobFitResult fit = FitBlob(image, bit_depth, *features, blur, CrosstalkOf(b), PsfOf(b));
  if (!fit.ok) return false;
  features->moment_major_var_px2 = fit.major_var_px2 + blur;
  features->moment_minor_var_px2 = fit.minor_var_px2 + blur;
  features->size_blur_var_px2 = blur;
  features->trace_var_px2 = fit.trace_var_px2 + blur;
  features->trace_var_se_px2 = fit.trace_var_se_px2;
  features->major_var_se_px2 = fit.major_var_se_px2;
  features->disc_raw_major_var_px2 = fit.raw_major_var_px2;
  features->disc_raw_minor_var_px2 = fit.raw_minor_var_px2;
  features->disc_raw_angle_deg = fit.angle_deg;
  features->disc_aniso_noise_var = fit.anisotropy_noise_var;
  // The fitted axes' direction with their variances: the moments' own is another (noisier, for a
  // near-round blob unrelated) measurement, and the line of sight turns the matrix of the two.
  if (features->ellipse_moments.valid) features->ellipse_moments.angle_deg = fit.angle_deg;
  return true;
}

}  // namespace irdist
