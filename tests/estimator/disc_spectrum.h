#pragma once
// An independent, noise-free renderer of a blob for the edge-phase tests: a uniformly
// bright elliptical disc, blurred by an optical Gaussian (and a defocus disc, if any) BEFORE the
// pixels sample it, integrated over each pixel's square, then spread by inter-pixel crosstalk (a
// discrete Gaussian) AFTER the sampling. Computed in the Fourier domain, exactly: the disc's
// transform is closed form
// (|M| J1(2 pi |M^T f|) / |M^T f| for the ellipse x = M u of the unit disc), the optical blur
// multiplies it by exp(-2 pi^2 s^2 |f|^2), the pixel's square by sinc(fx) sinc(fy); sampling at
// the pixel centres folds the spectrum (the sum over the aliases f + k, k integer, which is what
// makes a sharp image's sampled size depend on where its edge falls inside a pixel), and the
// crosstalk multiplies the folded spectrum by its kernel's own transform (a sampled Gaussian, or a
// lattice random walk). Nothing of the
// virtual rig's renderer (strips, erf) or of the estimator's edge model is used.

#include <algorithm>
#include <cmath>
#include <complex>
#include <vector>

#include <boost/math/special_functions/bessel.hpp>
#include <opencv2/core.hpp>

namespace irdist::testing {

struct DiscBlob {
  double cx = 0.0, cy = 0.0;        // centre, pixel-centre coordinates (pixel (0,0) at 0)
  double a = 5.0, b = 5.0;          // semi-axes, px
  double angle_deg = 0.0;           // major axis direction from +x
  double optics_sigma_px = 0.7;     // Gaussian blur before the pixels
  // An elliptical (astigmatic) optical PSF: its anisotropic covariance added to the round one's
  // sigma^2 I, S = sigma^2 I + [[psf_aniso_c_px2, psf_aniso_s_px2], [psf_aniso_s_px2,
  // -psf_aniso_c_px2]] (px^2; c = (Sxx - Syy) / 2, s = Sxy): transform exp(-2 pi^2 f^T S f).
  double psf_aniso_c_px2 = 0.0;
  double psf_aniso_s_px2 = 0.0;
  // A defocused lens: a uniform disc PSF of this radius (px) before the pixels as well, transform
  // 2 J1(x) / x at x = 2 pi r |f| (0: none).
  double defocus_disc_px = 0.0;
  // A diffraction-limited lens: a circular pupil's transfer function (2 / pi) (acos q - q
  // sqrt(1 - q^2)), q = |f| / cut-off, zero beyond this cut-off (cycles / px; 0: none).
  double airy_cutoff_cycles_per_px = 0.0;
  double crosstalk_sigma_px = 0.0;  // discrete Gaussian after them (sampled, normalised)
  // true: the crosstalk is a lattice random walk of variance crosstalk_sigma_px^2 instead (charge
  // hopping between neighbours: transform exp(-t (1 - cos 2 pi f)) per axis).
  bool crosstalk_lattice = false;
};

// A round defocus disc PSF's transform (radius `radius_px`) at the frequency |f| (cycles / px):
// 2 J1(x) / x, x = 2 pi r |f|.
inline double DefocusDiscTransform(double radius_px, double f) {
  const double x = 2.0 * M_PI * radius_px * f;
  return x < 1e-12 ? 1.0 : 2.0 * boost::math::cyl_bessel_j(1, x) / x;
}

// A circular pupil's transfer function (the Airy pattern's) of cut-off `cutoff` (cycles / px) at
// |f|: (2 / pi) (acos q - q sqrt(1 - q^2)), q = |f| / cutoff, 0 beyond; 1 for no cut-off (0).
inline double PupilTransform(double cutoff, double f) {
  if (cutoff <= 0.0) return 1.0;
  const double q = f / cutoff;
  return q >= 1.0 ? 0.0 : 2.0 / M_PI * (std::acos(q) - q * std::sqrt(1.0 - q * q));
}

// The crosstalk kernel's transform: a Gaussian of sigma sampled at the integers and normalised to
// sum 1, over |n| <= 8 sigma + 1.
inline double CrosstalkTransform(double sigma, double f) {
  if (sigma <= 0.0) return 1.0;
  const int reach = static_cast<int>(std::ceil(8.0 * sigma)) + 1;
  double sum = 1.0, value = 1.0;
  for (int n = 1; n <= reach; ++n) {
    const double w = std::exp(-0.5 * n * n / (sigma * sigma));
    sum += 2.0 * w;
    value += 2.0 * w * std::cos(2.0 * M_PI * f * n);
  }
  return value / sum;
}

// The variance of that sampled, normalised Gaussian (below 0.5 px it is less than sigma^2).
inline double CrosstalkVariance(double sigma) {
  if (sigma <= 0.0) return 0.0;
  const int reach = static_cast<int>(std::ceil(8.0 * sigma)) + 1;
  double sum = 1.0, second = 0.0;
  for (int n = 1; n <= reach; ++n) {
    const double w = std::exp(-0.5 * n * n / (sigma * sigma));
    sum += 2.0 * w;
    second += 2.0 * w * n * n;
  }
  return second / sum;
}

// Peak to peak of a sweep's values.
inline double PeakToPeak(const std::vector<double>& values) {
  const auto [lo, hi] = std::minmax_element(values.begin(), values.end());
  return *hi - *lo;
}

// One alias's term of the blob's folded spectrum at the frequency (fx, fy) (cycles per pixel): the
// disc's transform times the optics' and the pixel's square's, shifted to the disc's centre. c and
// s are the cosine and sine of the major axis's angle.
inline std::complex<double> DiscAliasTerm(const DiscBlob& blob, double c, double s, double fx,
                                          double fy) {
  // M^T f for M = R diag(a, b): (a (c fx + s fy), b (-s fx + c fy)).
  const double u = blob.a * (c * fx + s * fy), v = blob.b * (-s * fx + c * fy);
  const double rho = std::hypot(u, v);
  const double disc = rho < 1e-12
                          ? M_PI * blob.a * blob.b
                          : blob.a * blob.b * boost::math::cyl_bessel_j(1, 2.0 * M_PI * rho) / rho;
  const double f_s_f = blob.optics_sigma_px * blob.optics_sigma_px * (fx * fx + fy * fy) +
                       blob.psf_aniso_c_px2 * (fx * fx - fy * fy) +
                       2.0 * blob.psf_aniso_s_px2 * fx * fy;
  const double optics = std::exp(-2.0 * M_PI * M_PI * f_s_f) *
                        DefocusDiscTransform(blob.defocus_disc_px, std::hypot(fx, fy)) *
                        PupilTransform(blob.airy_cutoff_cycles_per_px, std::hypot(fx, fy));
  const double sx = fx == 0.0 ? 1.0 : std::sin(M_PI * fx) / (M_PI * fx);
  const double sy = fy == 0.0 ? 1.0 : std::sin(M_PI * fy) / (M_PI * fy);
  const double phase = -2.0 * M_PI * (fx * blob.cx + fy * blob.cy);
  return disc * optics * sx * sy * std::polar(1.0, phase);
}

// The crosstalk's transform at the sampled frequency (fx0, fy0): the lattice random walk's or the
// sampled Gaussian's, per the blob's crosstalk_lattice.
inline double CrosstalkFactor(const DiscBlob& blob, double fx0, double fy0) {
  if (blob.crosstalk_lattice) {
    const double t = blob.crosstalk_sigma_px * blob.crosstalk_sigma_px;
    return std::exp(-t * (2.0 - std::cos(2.0 * M_PI * fx0) - std::cos(2.0 * M_PI * fy0)));
  }
  return CrosstalkTransform(blob.crosstalk_sigma_px, fx0) *
         CrosstalkTransform(blob.crosstalk_sigma_px, fy0);
}

// The real part of the inverse discrete Fourier transform of a side x side spectrum (row-major,
// index ky * side + kx): g(n) = (1 / side^2) sum_k folded(k / side) e^{2 pi i k n / side},
// separably.
inline cv::Mat1d InverseSpectrum(const std::vector<std::complex<double>>& spectrum, int side) {
  std::vector<std::complex<double>> rows(spectrum.size());
  for (int ky = 0; ky < side; ++ky) {
    for (int x = 0; x < side; ++x) {
      std::complex<double> sum = 0.0;
      for (int kx = 0; kx < side; ++kx) {
        sum += spectrum[static_cast<size_t>(ky) * side + kx] *
               std::polar(1.0, 2.0 * M_PI * kx * x / side);
      }
      rows[static_cast<size_t>(ky) * side + x] = sum;
    }
  }
  cv::Mat1d out(side, side);
  for (int y = 0; y < side; ++y) {
    for (int x = 0; x < side; ++x) {
      std::complex<double> sum = 0.0;
      for (int ky = 0; ky < side; ++ky) {
        sum += rows[static_cast<size_t>(ky) * side + x] *
               std::polar(1.0, 2.0 * M_PI * ky * y / side);
      }
      out(y, x) = sum.real() / (static_cast<double>(side) * side);
    }
  }
  return out;
}

// Mean value per pixel (disc of unit brightness: the sum is the disc's area pi a b) on an
// side x side grid; the blob must lie well inside it (the grid is periodic).
inline cv::Mat1d RenderDiscSpectrum(const DiscBlob& blob, int side) {
  const double c = std::cos(blob.angle_deg * M_PI / 180.0);
  const double s = std::sin(blob.angle_deg * M_PI / 180.0);
  const int aliases = 3;  // |k| <= 3: beyond, the optical Gaussian (>= 0.3 px) leaves < 2e-5
  std::vector<std::complex<double>> spectrum(static_cast<size_t>(side) * side);
  for (int ky = 0; ky < side; ++ky) {
    const double fy0 = (ky < side / 2 ? ky : ky - side) / static_cast<double>(side);
    for (int kx = 0; kx < side; ++kx) {
      const double fx0 = (kx < side / 2 ? kx : kx - side) / static_cast<double>(side);
      std::complex<double> folded = 0.0;
      for (int ay = -aliases; ay <= aliases; ++ay) {
        for (int ax = -aliases; ax <= aliases; ++ax) {
          folded += DiscAliasTerm(blob, c, s, fx0 + ax, fy0 + ay);
        }
      }
      folded *= CrosstalkFactor(blob, fx0, fy0);
      spectrum[static_cast<size_t>(ky) * side + kx] = folded;
    }
  }
  return InverseSpectrum(spectrum, side);
}

// The rendered blob as a 16-bit frame: background + amplitude x value, rounded.
inline cv::Mat DiscFrame16(const cv::Mat1d& value, double amplitude, double background) {
  cv::Mat out(value.size(), CV_16UC1);
  for (int y = 0; y < value.rows; ++y) {
    for (int x = 0; x < value.cols; ++x) {
      out.at<std::uint16_t>(y, x) = static_cast<std::uint16_t>(
          std::clamp(std::round(background + amplitude * value(y, x)), 0.0, 65535.0));
    }
  }
  return out;
}

}  // namespace irdist::testing
