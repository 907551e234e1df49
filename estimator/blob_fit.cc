#include "estimator/blob_fit.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "base/pi.h"
#include "estimator/blob_fit_errors.h"
#include "estimator/crosstalk_kernel.h"
#include "estimator/normal_lm.h"
#include "estimator/normal_table.h"
#include "estimator/psf_anisotropy.h"

namespace irdist {
namespace {

// A pass stops when a step changes the chi^2 by less than this, or when the next Gauss-Newton
// step would (its Newton decrement, estimator/normal_lm.h: one model evaluation fewer a pass, 4
// instead of 6 a fit on bench_estimator's blob): a parameter is then within about 1% of its
// standard error of the minimum (both tolerances absolute, in |f|^2 units).
constexpr double kChi2Tolerance = 1e-4;
// A pass whose solution only sets the next pass's weights stops sooner (6.2 model evaluations a
// fit instead of 7.1 on bench_estimator's blob): the weights are the model's signal, which a
// step changing the chi^2 by this little moves by a small fraction of a noise sd, and the last
// pass converges to its tolerance whatever its start.
constexpr double kWeightsPassTolerance = 0.5;
// Parameters: centre x, y (relative to the fit's origin), P11, P12, P22, amplitude, background.
constexpr int kParams = 7;

// The quantities of one pixel's edge geometry SquareMean and its derivatives share.
struct EdgeGeometry {
  double dx, dy, gx, gy, pgx, pgy, r, n, dist, kappa;
};

// d t / d (x, y, P11, P12, P22) times `slope` at one pixel, for SquareMean's edge offset
// t = dist - shift kappa r: by the chain rule through q = (p - c)^T P (p - c), g = P (p - c),
// n = |g|, dist = (sqrt q - q) / n, the level set's curvature kappa = (n^2 tr P - g^T P g) / n^3
// and the edge's, kappa r (r = sqrt q). slope: the model's derivative along t.
void DiscDerivatives(const double* v, const EdgeGeometry& e, double slope, double shift,
                     double* d) {
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
    const double dkappa_edge = e.r * dkappa + e.kappa * dq[k] * 0.5 / e.r;
    d[k] = slope * (ddist - shift * dkappa_edge);
  }
}

struct Pixel {
  double x, y, value;
};

// How a pixel responds to the blurred disc: the optical blur's sd before the pixels
// sample the image, each pixel's square integrating it, then the inter-pixel crosstalk after the
// sampling, a separable kernel on the pixel grid. A model that folds the pixel's square and the
// crosstalk into one Gaussian before the sampling (the earlier fit) takes a sharp image's
// sampled edge for a smooth one: the fitted size then swings with the edge's sub-pixel phase.
// Integrated and spread in this order, the model's pixels are the camera's, whatever the mix.
struct PixelResponse {
  double optics_sd = 0.0;
  // The optics' PSF anisotropy (px^2, psf_anisotropy.h): an edge of normal n is blurred by the
  // variance n^T S n = optics_sd^2 + aniso_c (nx^2 - ny^2) + 2 aniso_s nx ny.
  double aniso_c = 0.0, aniso_s = 0.0;
  std::vector<double> kernel;   // crosstalk, 1-D (applied along x, then y), odd, sums to 1
  int reach = 0;                // the kernel's half width
};

// The response for a blur of `blur_var_px2` per axis (pixel area included) of which
// `crosstalk_var_px2` comes after the sampling: the optics' sd and the crosstalk's kernel.
PixelResponse MakeResponse(double blur_var_px2, double crosstalk_var_px2, double lattice_share) {
  PixelResponse r;
  r.optics_sd =
      std::sqrt(std::max(blur_var_px2 - kPixelAreaVarPx2 - crosstalk_var_px2, kMinOpticsVarPx2));
  r.kernel = {1.0};
  if (!(crosstalk_var_px2 > 1e-6)) return r;
  r.kernel = CrosstalkKernel(crosstalk_var_px2, lattice_share);
  r.reach = static_cast<int>(r.kernel.size() / 2);
  return r;
}

// Psi' = Phi and Lambda' = Psi: the first and second integrals of the normal CDF, at one x (Phi
// and phi from the table of estimator/normal_table.h: through erfc and exp they were half of the
// fit's time).
struct EdgeIntegrals {
  explicit EdgeIntegrals(double x) {
    const NormalValues normal = NormalAt(x);
    cdf = normal.cdf;
    const double pdf = normal.pdf;
    psi = x * cdf + pdf;
    lambda = 0.5 * ((x * x + 1.0) * cdf + x * pdf);
  }
  double cdf, psi, lambda;
};

// The mean of Phi((t + U) / sd) over a pixel's square, U the square's projection on the edge's
// normal (nx, ny): the sum of two uniforms of widths |nx| and |ny|, in closed form through Lambda
// (Psi when the edge runs along a pixel axis); its derivative along t into *slope.
double SquareEdge(double t, double nx, double ny, double sd, double* slope) {
  const double a = std::max(std::fabs(nx), std::fabs(ny));
  const double b = std::min(std::fabs(nx), std::fabs(ny));
  if (b < 1e-4) {  // one uniform of width a (~1)
    const EdgeIntegrals hi((t + 0.5 * a) / sd), lo((t - 0.5 * a) / sd);
    *slope = (hi.cdf - lo.cdf) / a;
    return sd / a * (hi.psi - lo.psi);
  }
  const EdgeIntegrals e[4] = {EdgeIntegrals((t + 0.5 * (a + b)) / sd),
                              EdgeIntegrals((t + 0.5 * (a - b)) / sd),
                              EdgeIntegrals((t - 0.5 * (a - b)) / sd),
                              EdgeIntegrals((t - 0.5 * (a + b)) / sd)};
  const double c = sd / (a * b);
  *slope = c * (e[0].psi - e[1].psi - e[2].psi + e[3].psi);
  return c * sd * (e[0].lambda - e[1].lambda - e[2].lambda + e[3].lambda);
}

// One edge point's mean over the pixel's square for the PSF's anisotropy along its normal,
// aniso_n = n^T a n (a the traceless part of the PSF's covariance): the edge spreads by the
// variance along its normal, optics_var + aniso_n, and its 50% point moves inward by the curvature
// times the variance along its tangent, optics_var - aniso_n, over 2 (a curved edge's blur reaches
// in along the tangent; an elliptical PSF thus moves the edge by different amounts around the
// disc), plus the square's tangential 1/12 over 2; the curvature widens it to second order.
struct BlurredEdge {
  double value = 0.0, slope = 0.0, shift = 0.0;
};
BlurredEdge BlurEdge(double dist, double kappa_edge, double nx, double ny, double optics_var,
                     double aniso_n) {
  const double normal2 = std::max(optics_var + aniso_n, kMinOpticsVarPx2);
  const double tangent2 = std::max(optics_var - aniso_n, kMinOpticsVarPx2);
  BlurredEdge e;
  e.shift = 0.5 * tangent2 + 0.5 * kPixelAreaVarPx2;
  // To second order the curvature also widens the edge: the tangential offset Y (blur and square)
  // moves it by kappa Y^2 / 2, whose variance kappa^2 var(Y^2) / 4 adds to the edge's (var(Y^2) =
  // 2 sd^4 + sd^2 / 3 + 1/80 - 1/144 for a Gaussian of sd plus a uniform of width 1).
  const double var_y2 = 2.0 * tangent2 * tangent2 + tangent2 / 3.0 + 1.0 / 80.0 - 1.0 / 144.0;
  const double sd =
      std::sqrt(normal2) * (1.0 + kappa_edge * kappa_edge * var_y2 / (8.0 * normal2));
  e.value = SquareEdge(dist - e.shift * kappa_edge, nx, ny, sd, &e.slope);
  return e;
}

// Adds to d[5] the model's change through the edge normal's turn with v (x, y, P11, P12, P22):
// aniso_n = c (nx^2 - ny^2) + 2 s nx ny moves with n = g / |g|; dvalue_daniso its effect.
void AddNormalTurn(const double* v, double dx, double dy, double nx, double ny, double n,
                   const PixelResponse& r, double dvalue_daniso, double* d) {
  const double dgx[5] = {-v[2], -v[3], dx, dy, 0.0};
  const double dgy[5] = {-v[3], -v[4], 0.0, dx, dy};
  for (int k = 0; k < 5; ++k) {
    const double along = nx * dgx[k] + ny * dgy[k];
    const double dnx = (dgx[k] - nx * along) / n, dny = (dgy[k] - ny * along) / n;
    const double daniso =
        2.0 * r.aniso_c * (nx * dnx - ny * dny) + 2.0 * r.aniso_s * (dnx * ny + nx * dny);
    d[k] += dvalue_daniso * daniso;
  }
}

// The disc's mean over the pixel at (x, y) before crosstalk, and its derivatives into d[5]: the
// optical edge integrated over the pixel's square as a straight edge (SquareEdge) at the signed
// distance to the disc's edge, blurred and shifted as BlurEdge says (the PSF's variance along the
// edge's normal and tangent: an elliptical PSF's differ around the disc). The derivatives
// (analytic, the chain rule through q = (p - c)^T P (p - c), g = P (p - c), the first-order
// distance and the curvature; DiscDerivatives; an elliptical PSF's turn with the normal by a
// central difference in n^T a n) leave out the turn of the edge's normal across the square and
// the widening's change: a few % of the slope, which moves the fit's path, not its solution on an
// exact model. A pixel whose square lies far from the edge (5 sd, Phi(-5) = 3e-7, plus the
// square's half diagonal and 0.5 px for the first-order distance) is 1 or 0 at once.
double SquareMean(const double* v, double x, double y, const PixelResponse& r, double* d) {
  const double dx = x - v[0], dy = y - v[1];
  const double gx = v[2] * dx + v[3] * dy, gy = v[3] * dx + v[4] * dy;  // g = P (p - c)
  const double q = dx * gx + dy * gy;
  const double n2 = gx * gx + gy * gy;
  const double rq = std::sqrt(q), n = std::sqrt(n2);
  const double dist = (rq - q) / n;
  const double optics_var = r.optics_sd * r.optics_sd;
  const double aniso = std::hypot(r.aniso_c, r.aniso_s);
  const double margin = 1.25 + 5.0 * std::sqrt(optics_var + aniso);
  std::fill(d, d + 5, 0.0);
  if (q < 0.09 || dist > margin || dist < -margin) return dist < 0.0 ? 0.0 : 1.0;
  const double pgx = v[2] * gx + v[3] * gy, pgy = v[3] * gx + v[4] * gy;  // P g
  // The curvature of the level set through the pixel, scaled to the disc's edge (the level sets
  // of q are the edge scaled by sqrt q): the edge's own curvature bends the blur's reach.
  const double kappa = (n2 * (v[2] + v[4]) - (gx * pgx + gy * pgy)) / (n2 * n);
  const double kappa_edge = kappa * rq;
  const double nx = gx / n, ny = gy / n;
  const double aniso_n = r.aniso_c * (nx * nx - ny * ny) + 2.0 * r.aniso_s * nx * ny;
  const BlurredEdge e = BlurEdge(dist, kappa_edge, nx, ny, optics_var, aniso_n);
  DiscDerivatives(v, {dx, dy, gx, gy, pgx, pgy, rq, n, dist, kappa}, e.slope, e.shift, d);
  if (aniso > 0.0) {
    const double h = 1e-4 * (optics_var + aniso);
    const double up = BlurEdge(dist, kappa_edge, nx, ny, optics_var, aniso_n + h).value;
    const double down = BlurEdge(dist, kappa_edge, nx, ny, optics_var, aniso_n - h).value;
    AddNormalTurn(v, dx, dy, nx, ny, n, r, (up - down) / (2.0 * h), d);
  }
  return e.value;
}

// `in` (rows x cols, row-major) convolved with `kernel` along x (dx = 1) or y, keeping the valid
// part, into `out`: (rows x (cols - 2 reach)) or ((rows - 2 reach) x cols).
void Convolve(const double* in, int rows, int cols, const std::vector<double>& kernel,
              bool along_x, double* out) {
  const int reach = static_cast<int>(kernel.size() / 2);
  const int out_rows = along_x ? rows : rows - 2 * reach;
  const int out_cols = along_x ? cols - 2 * reach : cols;
  const int stride = along_x ? 1 : cols;
  for (int row = 0; row < out_rows; ++row) {
    for (int col = 0; col < out_cols; ++col) {
      const double* first = &in[static_cast<size_t>(row) * cols + col];
      double acc = 0.0;
      for (size_t k = 0; k < kernel.size(); ++k) acc += kernel[k] * first[k * stride];
      out[static_cast<size_t>(row) * out_cols + col] = acc;
    }
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
        const double r = (v[6] + v[5] * mean[i] - pixels_[i].value) * inv_sd_[i];
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
      const double r = (v[6] + v[5] * mean[i] - pixels_[i].value) * s;
      cost2 += r * r;
      const double* d = &d_mean_[i];
      if (d[0] == 0.0 && d[n] == 0.0 && d[2 * n] == 0.0 && d[3 * n] == 0.0 && d[4 * n] == 0.0) {
        const double ms = mean[i] * s;
        flat_mm += ms * ms, flat_m += ms * s, flat_1 += s * s, flat_mr += ms * r, flat_r += s * r;
        continue;
      }
      const double amplitude_s = v[5] * s;
      for (int k = 0; k < 5; ++k) j[k] = amplitude_s * d[k * n];
      j[5] = mean[i] * s;
      j[6] = s;
      for (int k = 0; k < kParams; ++k) {
        jtr[k] += j[k] * r;
        for (int l = k; l < kParams; ++l) jtj[k * kParams + l] += j[k] * j[l];
      }
    }
    jtj[5 * kParams + 5] += flat_mm, jtj[5 * kParams + 6] += flat_m, jtj[6 * kParams + 6] += flat_1;
    jtr[5] += flat_mr, jtr[6] += flat_r;
    for (int k = 0; k < kParams; ++k) {
      normal->jtr(k) = jtr[k];
      for (int l = k; l < kParams; ++l) {
        normal->jtj(k, l) = normal->jtj(l, k) = jtj[k * kParams + l];
      }
    }
    normal->cost2 = cost2;
    return std::isfinite(cost2);
  }
  // Each pixel's model mean (relative to the amplitude) at v; nothing is computed when v is the
  // last point.
  const std::vector<double>& MeansAt(const double* v) const {
    if (!computed_ || !std::equal(v, v + kParams, at_)) Compute(v);
    return mean_;
  }

 private:
  // The model on the window grown by the crosstalk's reach (planes: the mean, then its five
  // derivatives), each pixel's square integrated, then spread by the crosstalk onto the window.
  // Without crosstalk the grid is the window and the planes are mean_ and d_mean_ themselves.
  void Compute(const double* v) const {
    const int reach = response_.reach;
    const int cols = cols_ + 2 * reach, rows = rows_ + 2 * reach;
    const size_t grid = static_cast<size_t>(cols) * rows;
    if (reach > 0) grown_.resize(6 * grid), across_.resize(static_cast<size_t>(rows) * cols_);
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
      Convolve(grown_.data() + p * grid, rows, cols, response_.kernel, true, across_.data());
      Convolve(across_.data(), rows, cols_, response_.kernel, false,
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

using Covariance = BlobCovariance;
static_assert(kParams == BlobCovariance::RowsAtCompileTime, "the covariance's parameters");

// The parameters' covariance at the solution, (J^T J)^-1 of the weighted residuals (as
// ceres::Covariance, without its sparse machinery: J^T J's eigen-decomposition); false when J^T J
// is singular to Ceres's own threshold (reciprocal condition 1e-14).
bool FitCovariance(const WindowResiduals& residuals, const double* v, Covariance* c) {
  NormalEquations<kParams> normal;
  residuals.Evaluate(v, true, &normal);
  const Eigen::SelfAdjointEigenSolver<Covariance> eigen(normal.jtj);
  if (eigen.info() != Eigen::Success) return false;
  const Eigen::Matrix<double, kParams, 1> lambda = eigen.eigenvalues();  // ascending
  if (!(lambda(0) > 1e-14 * lambda(kParams - 1))) return false;
  *c = eigen.eigenvectors() * lambda.cwiseInverse().asDiagonal() * eigen.eigenvectors().transpose();
  return true;
}

// One weighted least-squares pass (ceres::TinySolver) from v; returns the weighted cost per pixel.
// covariance: when set, receives FitCovariance at the pass's solution (*covariance_ok whether
// it could be computed).
double SolvePass(const WindowResiduals& residuals, double* v, bool* ok,
                 Covariance* covariance = nullptr, bool* covariance_ok = nullptr,
                 double tolerance = kChi2Tolerance) {
  NormalLmOptions options;
  options.function_tolerance = tolerance;
  options.decrement_tolerance = tolerance;
  Eigen::Matrix<double, kParams, 1> x(v);
  const NormalLmSummary summary = SolveNormalLm(residuals, options, &x);
  std::copy(x.data(), x.data() + kParams, v);
  *ok = std::isfinite(summary.final_cost) && v[2] > 0.0 && v[4] > 0.0 && v[2] * v[4] > v[3] * v[3];
  if (*ok && covariance != nullptr) *covariance_ok = FitCovariance(residuals, v, covariance);
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

}  // namespace

double BlobEdgeValue(const double v[5], double x, double y, double optics_sd, double d[5],
                     const PsfAnisotropy& psf) {
  PixelResponse response;
  response.optics_sd = optics_sd;
  response.aniso_c = psf.c_px2;
  response.aniso_s = psf.s_px2;
  return SquareMean(v, x, y, response, d);
}

// FitBlob with `passes` IRLS passes (1: the read noise's weights alone, for FitBlurSplit).
BlobFitResult FitBlobPasses(const cv::Mat& image, int bit_depth, const Features& features,
                            double blur_var_px2, const Crosstalk& crosstalk, int passes,
                            const PsfAnisotropy& psf) {
  const double crosstalk_var_px2 = crosstalk.var_px2;
  BlobFitResult out;
  out.blur_var_px2 = blur_var_px2;
  const double gauss_var = blur_var_px2 - kPixelAreaVarPx2;
  if (!features.Usable() || !features.ellipse_moments.valid || image.type() != CV_16UC1 ||
      !(gauss_var > kMinOpticsVarPx2) || !(crosstalk_var_px2 >= 0.0)) {
    return out;
  }
  out.crosstalk_var_px2 = std::min(crosstalk_var_px2, gauss_var - kMinOpticsVarPx2);
  cv::Rect window;
  const std::vector<Pixel> pixels = BlobPixels(image, bit_depth, features, blur_var_px2, &window);
  double v[kParams];
  if (!StartFromMoments(features, blur_var_px2, window.tl(), v)) return out;
  const double reach = 2.0 * std::sqrt(features.moment_major_var_px2) + 3.0 * std::sqrt(gauss_var);
  const double scale = 1.0 / ((1 << bit_depth) - 1);
  const double read_var = std::max(ReadVariance(pixels, {v[0], v[1]}, reach), scale * scale / 12.0);
  PixelResponse response =
      MakeResponse(blur_var_px2, out.crosstalk_var_px2, crosstalk.lattice_share);
  response.aniso_c = psf.c_px2;
  response.aniso_s = psf.s_px2;
  WindowResiduals model(pixels, window.width, window.height, std::move(response));
  model.SetVariances(std::vector<double>(pixels.size(), read_var));
  bool ok = false, covariance_ok = false;
  double chi2 = 0.0;
  Covariance covariance;
  for (int pass = 0; pass < passes; ++pass) {
    chi2 = SolvePass(model, v, &ok, pass == 1 ? &covariance : nullptr, &covariance_ok,
                     pass + 1 == passes ? kChi2Tolerance : kWeightsPassTolerance);
    if (!ok) return out;
    if (pass == 0) out.read_weighted_chi2 = chi2;
    if (pass == 0 && passes > 1) model.SetVariances(NoiseVariances(pixels, model, v, read_var));
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
  out.pixels = static_cast<int>(pixels.size());
  return out;
}

BlobFitResult FitBlob(const cv::Mat& image, int bit_depth, const Features& features,
                      double blur_var_px2, const Crosstalk& crosstalk, const PsfAnisotropy& psf) {
  // IRLS, two passes: the read noise's weights, then the weights of the first pass's model (a
  // third pass, weights from the second's, moved no figure: docs/estimator.md "The blob fit").
  return FitBlobPasses(image, bit_depth, features, blur_var_px2, crosstalk, 2, psf);
}

PsfAnisotropy PsfOf(const BlurCalibration& b) {
  PsfAnisotropy psf;
  psf.c_px2 = b.psf_aniso_c_px2;
  psf.s_px2 = b.psf_aniso_s_px2;
  return psf;
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
  const BlobFitResult fit =
      FitBlob(image, bit_depth, *features, blur, {b.crosstalk_var_px2, b.crosstalk_lattice_share},
              PsfOf(b));
  if (!fit.ok) return false;
  features->moment_major_var_px2 = fit.major_var_px2 + blur;
  features->moment_minor_var_px2 = fit.minor_var_px2 + blur;
  features->size_blur_var_px2 = blur;
  features->trace_var_px2 = fit.trace_var_px2 + blur;
  features->trace_var_se_px2 = fit.trace_var_se_px2;
  features->major_var_se_px2 = fit.major_var_se_px2;
  // The fitted axes' direction with their variances: the moments' own is another (noisier, for a
  // near-round blob unrelated) measurement, and the line of sight turns the matrix of the two.
  if (features->ellipse_moments.valid) features->ellipse_moments.angle_deg = fit.angle_deg;
  return true;
}

}  // namespace irdist
