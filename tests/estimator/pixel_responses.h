#pragma once
// Renderers whose pixel response is NOT the blob fit's: a flat disc of radius R
// seen through one of five responses outside the fit's family (an optical Gaussian before the
// pixels, each pixel's full square, a sampled Gaussian or lattice walk after them). Each is built
// from the physics of its parts, never from the estimator's edge model or the virtual rig:
//
// - kAllBlurAfter: no optics; each pixel integrates the sharp disc over its square, exactly
//   (the disc's area inside the square, in closed form: CircleRectArea); then a sampled Gaussian
//   of sigma 1.0 px on the pixel grid, truncated at 4 sigma and normalised (a blur of the sampled
//   image: charge spread after the pixels).
// - kDefocusDisc: a uniform disc PSF (geometric defocus) of radius 1.4 px before the pixels
//   (transform 2 J1(2 pi rho f) / (2 pi rho f); variance rho^2 / 4 = 0.49 px^2 per axis).
// - kAiry: the diffraction PSF of a circular pupil, whose transform is the pupil's
//   autocorrelation (2 / pi) (acos s - s sqrt(1 - s^2)), s = f / f_c, zero beyond the cut-off
//   f_c = 0.7 cycles / px (the core's sd about 0.42 / f_c = 0.6 px; tails r^-3).
// - kFillFactor70: a pixel aperture 70% of the pitch (a 0.7 x 0.7 px square: sinc(0.7 f) per
//   axis) behind an optical Gaussian of 0.5 px.
// - kAstigmatic: an optical Gaussian of 0.70 px along x and 0.77 px along y (10% apart).
//
// The optical cases are rendered in the Fourier domain as tests/estimator/disc_spectrum.h does:
// the disc's transform R J1(2 pi R |f|) / |f| times the PSF's and the aperture's transforms,
// folded by the sampling (the aliases f + k, |k| <= kAliases of the response: where the product
// has decayed; the Airy transform is zero beyond 0.7 cycles / px, so its fold is exact), phased to
// the disc's centre and brought back by an inverse DFT. NoisyFrame12 adds EMVA 1288 noise
// (Poisson shot noise, Gaussian read noise, system gain, 12-bit quantisation) for calibration
// frames; CleanFrame12 rounds the noise-free image to whole DN.

#include <algorithm>
#include <boost/math/special_functions/bessel.hpp>
#include <cmath>
#include <complex>
#include <cstdint>
#include <map>
#include <opencv2/core.hpp>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "tests/estimator/disc_spectrum.h"

namespace irdist::testing {

enum class PixelResponseKind { kAllBlurAfter, kDefocusDisc, kAiry, kFillFactor70, kAstigmatic };

inline std::vector<PixelResponseKind> AllPixelResponses() {
  return {PixelResponseKind::kAllBlurAfter, PixelResponseKind::kDefocusDisc,
          PixelResponseKind::kAiry, PixelResponseKind::kFillFactor70,
          PixelResponseKind::kAstigmatic};
}

inline std::string ResponseName(PixelResponseKind kind) {
  switch (kind) {
    case PixelResponseKind::kAllBlurAfter: return "all blur after the pixels (1.0 px, 4 sd)";
    case PixelResponseKind::kDefocusDisc: return "defocus disc PSF (radius 1.4 px)";
    case PixelResponseKind::kAiry: return "Airy PSF (cut-off 0.7 cycles/px)";
    case PixelResponseKind::kFillFactor70: return "pixel aperture 70% (optics 0.5 px)";
    case PixelResponseKind::kAstigmatic: return "astigmatic optics (0.70 / 0.77 px)";
  }
  return "?";
}

// A flat, uniformly bright disc: centre in pixel-centre coordinates (pixel (0, 0)'s centre at 0),
// radius in px.
struct FlatDisc {
  double cx = 0.0, cy = 0.0;
  double radius_px = 5.0;
};

// The area of the disc of radius r centred at the origin inside [x0, x1] x [y0, y1], exact:
// the chord's height integrated along x in closed form (the integral of sqrt(r^2 - x^2) is
// (x sqrt(r^2 - x^2) + r^2 asin(x / r)) / 2), piecewise between the x where the circle crosses
// y0 or y1.
inline double CircleRectArea(double r, double x0, double x1, double y0, double y1) {
  const auto chord = [r](double x) {
    x = std::clamp(x, -r, r);
    return 0.5 * (x * std::sqrt(std::max(r * r - x * x, 0.0)) + r * r * std::asin(x / r));
  };
  const double lo = std::max(x0, -r), hi = std::min(x1, r);
  if (!(hi > lo) || !(y1 > y0)) return 0.0;
  std::vector<double> xs = {lo, hi};
  for (const double y : {y0, y1}) {
    if (std::fabs(y) >= r) continue;
    const double h = std::sqrt(r * r - y * y);
    for (const double x : {-h, h}) {
      if (x > lo && x < hi) xs.push_back(x);
    }
  }
  std::sort(xs.begin(), xs.end());
  double area = 0.0;
  for (size_t i = 0; i + 1 < xs.size(); ++i) {
    const double a = xs[i], b = xs[i + 1];
    const double m = 0.5 * (a + b), h = std::sqrt(std::max(r * r - m * m, 0.0));
    if (!(std::min(y1, h) > std::max(y0, -h))) continue;
    const double top = y1 < h ? y1 * (b - a) : chord(b) - chord(a);
    const double bottom = y0 > -h ? y0 * (b - a) : -(chord(b) - chord(a));
    area += top - bottom;
  }
  return area;
}

// The sampled Gaussian of sd `sd` on the integers |n| <= 4 sd (truncated), normalised.
inline std::vector<double> TruncatedSampledGaussian(double sd) {
  const int reach = static_cast<int>(std::floor(4.0 * sd));
  std::vector<double> kernel(2 * reach + 1);
  double sum = 0.0;
  for (int n = -reach; n <= reach; ++n) {
    sum += kernel[n + reach] = std::exp(-0.5 * n * n / (sd * sd));
  }
  for (double& w : kernel) w /= sum;
  return kernel;
}

// A kernel's variance on the grid.
inline double KernelVariance(const std::vector<double>& kernel) {
  const int reach = static_cast<int>(kernel.size() / 2);
  double var = 0.0;
  for (int n = -reach; n <= reach; ++n) var += kernel[n + reach] * n * n;
  return var;
}

// The transform of the response's optics and pixel aperture (everything before the sampling, the
// disc aside) at frequency (fx, fy), cycles / px.
inline double BeforeSamplingTransform(PixelResponseKind kind, double fx, double fy) {
  const auto sinc = [](double f) { return f == 0.0 ? 1.0 : std::sin(M_PI * f) / (M_PI * f); };
  const auto gauss = [](double sd, double f) { return std::exp(-2.0 * M_PI * M_PI * sd * sd * f * f); };
  const double rho = std::hypot(fx, fy);
  switch (kind) {
    case PixelResponseKind::kDefocusDisc:
      return DefocusDiscTransform(1.4, rho) * sinc(fx) * sinc(fy);
    case PixelResponseKind::kAiry:
      return PupilTransform(0.7, rho) * sinc(fx) * sinc(fy);
    case PixelResponseKind::kFillFactor70:
      return gauss(0.5, fx) * gauss(0.5, fy) * sinc(0.7 * fx) * sinc(0.7 * fy);
    case PixelResponseKind::kAstigmatic:
      return gauss(0.70, fx) * gauss(0.77, fy) * sinc(fx) * sinc(fy);
    case PixelResponseKind::kAllBlurAfter:
      return sinc(fx) * sinc(fy);
  }
  return 0.0;
}

// The aliases |k| the fold sums for a response: where the product with the disc's transform has
// decayed (measured: doubling them moves no pixel by more than 2e-5 of the disc's brightness, test
// PixelResponses.TheFoldHasConverged; the defocus disc's 4: 7e-6 at R = 4.6 px).
inline int AliasesOf(PixelResponseKind kind) {
  switch (kind) {
    case PixelResponseKind::kDefocusDisc: return 4;
    case PixelResponseKind::kAiry: return 1;  // band-limited to 0.7 cycles / px: exact
    case PixelResponseKind::kAllBlurAfter: return 24;  // only for the cross-check
    default: return 3;  // Gaussian optics of >= 0.5 px: exp(-2 pi^2 0.25 3.5^2) ~ 1e-26
  }
}

// The inverse DFT of a side x side spectrum (row-major, frequencies k / side), real part
// (OpenCV's, whose inverse runs e^{+2 pi i k n / side} and divides by side^2).
inline cv::Mat1d InverseDft(const std::vector<std::complex<double>>& spectrum, int side) {
  cv::Mat2d packed(side, side);
  for (int y = 0; y < side; ++y) {
    for (int x = 0; x < side; ++x) {
      const std::complex<double>& v = spectrum[static_cast<size_t>(y) * side + x];
      packed(y, x) = cv::Vec2d(v.real(), v.imag());
    }
  }
  cv::Mat complex_image;
  cv::dft(packed, complex_image, cv::DFT_INVERSE | cv::DFT_SCALE | cv::DFT_COMPLEX_OUTPUT);
  cv::Mat planes[2];
  cv::split(complex_image, planes);
  return cv::Mat1d(planes[0]);
}

// The folded frequencies of a response on a side x side grid, with the transform before the
// sampling at each (zeros left out): the same for every frame, so computed once (FoldTableOf).
struct FoldTable {
  struct Term {
    int bin;  // ky x side + kx
    int ax, ay;
    int rho_index;  // into rhos: the disc's transform depends on |f| alone
    double h;
  };
  std::vector<Term> terms;
  // The distinct |f| of the terms (the grid's symmetries repeat each): the disc's Bessel
  // transform is evaluated once per distinct |f| and frame, not per term.
  std::vector<double> rhos;
};

inline const FoldTable& FoldTableOf(PixelResponseKind kind, int side, int aliases) {
  static std::map<std::tuple<int, int, int>, FoldTable> cache;
  FoldTable& table = cache[{static_cast<int>(kind), side, aliases}];
  if (!table.terms.empty()) return table;
  std::map<double, int> index_of_rho;  // |f| -> index into rhos
  for (int ky = 0; ky < side; ++ky) {
    const double fy0 = (ky < side / 2 ? ky : ky - side) / static_cast<double>(side);
    for (int kx = 0; kx < side; ++kx) {
      const double fx0 = (kx < side / 2 ? kx : kx - side) / static_cast<double>(side);
      for (int ay = -aliases; ay <= aliases; ++ay) {
        for (int ax = -aliases; ax <= aliases; ++ax) {
          const double fx = fx0 + ax, fy = fy0 + ay;
          const double h = BeforeSamplingTransform(kind, fx, fy);
          if (h == 0.0) continue;
          const double rho = std::hypot(fx, fy);
          const auto at = index_of_rho.emplace(rho, static_cast<int>(table.rhos.size()));
          if (at.second) table.rhos.push_back(rho);
          table.terms.push_back({ky * side + kx, ax, ay, at.first->second, h});
        }
      }
    }
  }
  return table;
}

// The optical responses' image in the Fourier domain, with `aliases` folds (above): the disc's
// transform R J1(2 pi R rho) / rho times the table's, phased to the disc's centre (separably:
// e^{-2 pi i fx cx} e^{-2 pi i fy cy}).
inline cv::Mat1d RenderFolded(const FlatDisc& disc, PixelResponseKind kind, int side,
                              int aliases) {
  const double r = disc.radius_px;
  const int span = 2 * aliases + 1;
  std::vector<std::complex<double>> phase_x(static_cast<size_t>(side) * span),
      phase_y(static_cast<size_t>(side) * span);
  for (int k = 0; k < side; ++k) {
    const double f0 = (k < side / 2 ? k : k - side) / static_cast<double>(side);
    for (int a = -aliases; a <= aliases; ++a) {
      phase_x[static_cast<size_t>(k) * span + a + aliases] =
          std::polar(1.0, -2.0 * M_PI * (f0 + a) * disc.cx);
      phase_y[static_cast<size_t>(k) * span + a + aliases] =
          std::polar(1.0, -2.0 * M_PI * (f0 + a) * disc.cy);
    }
  }
  const FoldTable& table = FoldTableOf(kind, side, aliases);
  std::vector<double> disc_transform(table.rhos.size());
  for (size_t i = 0; i < table.rhos.size(); ++i) {
    const double rho = table.rhos[i];
    disc_transform[i] = rho < 1e-12 ? M_PI * r * r
                                    : r * boost::math::cyl_bessel_j(1, 2.0 * M_PI * r * rho) / rho;
  }
  std::vector<std::complex<double>> spectrum(static_cast<size_t>(side) * side);
  for (const FoldTable::Term& t : table.terms) {
    const int kx = t.bin % side, ky = t.bin / side;
    spectrum[t.bin] += disc_transform[t.rho_index] * t.h * phase_x[static_cast<size_t>(kx) * span + t.ax + aliases] *
                       phase_y[static_cast<size_t>(ky) * span + t.ay + aliases];
  }
  return InverseDft(spectrum, side);
}

// The sharp disc integrated over each pixel's square (side `aperture` px, centred on the pixel),
// exact, as the mean over the aperture.
inline cv::Mat1d RenderPixelAreas(const FlatDisc& disc, int side, double aperture) {
  cv::Mat1d out(side, side);
  const double h = 0.5 * aperture;
  for (int y = 0; y < side; ++y) {
    for (int x = 0; x < side; ++x) {
      out(y, x) = CircleRectArea(disc.radius_px, x - disc.cx - h, x - disc.cx + h,
                                 y - disc.cy - h, y - disc.cy + h) /
                  (aperture * aperture);
    }
  }
  return out;
}

// `image` convolved with `kernel` along x and along y on the grid, periodically.
inline cv::Mat1d ConvolvePeriodic(const cv::Mat1d& image, const std::vector<double>& kernel) {
  const int reach = static_cast<int>(kernel.size() / 2);
  const int side = image.rows;
  cv::Mat1d across(side, side, 0.0), out(side, side, 0.0);
  for (int y = 0; y < side; ++y) {
    for (int x = 0; x < side; ++x) {
      for (int n = -reach; n <= reach; ++n) {
        across(y, x) += kernel[n + reach] * image(y, ((x - n) % side + side) % side);
      }
    }
  }
  for (int y = 0; y < side; ++y) {
    for (int x = 0; x < side; ++x) {
      for (int n = -reach; n <= reach; ++n) {
        out(y, x) += kernel[n + reach] * across(((y - n) % side + side) % side, x);
      }
    }
  }
  return out;
}

// The kAllBlurAfter response's kernel after the pixels.
inline std::vector<double> AfterPixelsKernel() { return TruncatedSampledGaussian(1.0); }

// Mean value per pixel of the unit-bright disc through `kind` (the sum is the disc's area
// pi R^2), noise free, on a side x side grid (periodic: the blob well inside it).
inline cv::Mat1d RenderResponse(const FlatDisc& disc, PixelResponseKind kind, int side) {
  if (kind == PixelResponseKind::kAllBlurAfter) {
    return ConvolvePeriodic(RenderPixelAreas(disc, side, 1.0), AfterPixelsKernel());
  }
  return RenderFolded(disc, kind, side, AliasesOf(kind));
}

// The response's blur variance per axis (px^2, pixel area included) where it is finite: the
// model's "true" total blur, for the tolerance of a split. NaN for the Airy PSF (its variance
// diverges: the cumulants measure a finite window's).
inline double ResponseBlurVarPx2(PixelResponseKind kind) {
  switch (kind) {
    case PixelResponseKind::kAllBlurAfter: return 1.0 / 12.0 + KernelVariance(AfterPixelsKernel());
    case PixelResponseKind::kDefocusDisc: return 1.0 / 12.0 + 1.4 * 1.4 / 4.0;
    case PixelResponseKind::kFillFactor70: return 0.49 / 12.0 + 0.25;
    case PixelResponseKind::kAstigmatic: return 1.0 / 12.0 + 0.5 * (0.49 + 0.77 * 0.77);
    case PixelResponseKind::kAiry: return std::nan("");
  }
  return std::nan("");
}

// A camera after EMVA 1288: electrons = amplitude_e x value + dark_e, Poisson shot noise, Gaussian
// read noise, DN = gain x electrons + black, rounded and clipped to 12 bits.
struct Emva1288 {
  double amplitude_e = 7700.0;  // the flat disc's electrons (about 3000 DN at 0.39 DN / e-)
  double dark_e = 100.0;
  double read_noise_e = 7.0;
  double gain_dn_per_e = 0.39;
  double black_dn = 16.0;
};

// The noise-free frame, rounded to whole DN (12 bit).
inline cv::Mat CleanFrame12(const cv::Mat1d& value, const Emva1288& camera = {}) {
  cv::Mat out(value.size(), CV_16UC1);
  for (int y = 0; y < value.rows; ++y) {
    for (int x = 0; x < value.cols; ++x) {
      const double e = camera.amplitude_e * value(y, x) + camera.dark_e;
      out.at<std::uint16_t>(y, x) = static_cast<std::uint16_t>(
          std::clamp(std::round(camera.gain_dn_per_e * e + camera.black_dn), 0.0, 4095.0));
    }
  }
  return out;
}

// The same with the camera's noise drawn from rng.
inline cv::Mat NoisyFrame12(const cv::Mat1d& value, std::mt19937_64* rng,
                            const Emva1288& camera = {}) {
  cv::Mat out(value.size(), CV_16UC1);
  std::normal_distribution<double> read(0.0, camera.read_noise_e);
  for (int y = 0; y < value.rows; ++y) {
    for (int x = 0; x < value.cols; ++x) {
      const double mean_e = std::max(camera.amplitude_e * value(y, x) + camera.dark_e, 0.0);
      std::poisson_distribution<long> shot(mean_e);
      const double e = static_cast<double>(shot(*rng)) + read(*rng);
      out.at<std::uint16_t>(y, x) = static_cast<std::uint16_t>(
          std::clamp(std::round(camera.gain_dn_per_e * e + camera.black_dn), 0.0, 4095.0));
    }
  }
  return out;
}

// A 12-bit frame of a flat disc of `radius_px` centred at (cx, cy) through `kind` on a side x side
// grid: noise free (rounded to whole DN), or with the camera's noise drawn from `rng`.
inline cv::Mat DiscFrame12(double cx, double cy, double radius_px, PixelResponseKind kind, int side,
                           std::mt19937_64* rng = nullptr) {
  FlatDisc disc;
  disc.cx = cx;
  disc.cy = cy;
  disc.radius_px = radius_px;
  const cv::Mat1d value = RenderResponse(disc, kind, side);
  return rng == nullptr ? CleanFrame12(value) : NoisyFrame12(value, rng);
}

}  // namespace irdist::testing
