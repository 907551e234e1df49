#pragma once
// sim-internal (included by sim/*.cc only): the lens's point-spread function at one distance and
// the pixels' response to a disc's image through it (docs/virtual-rig.md "Optics"). Three families
// of real lenses, each from its optics:
// - an elliptical Gaussian core (astigmatism: two widths and the major axis's angle, constant in
//   pixels), with the thin-lens defocus added as a round Gaussian of variance c^2 / 16;
// - or the defocus as the geometric disc it is (a uniform disc of diameter c, the circle of
//   confusion, growing with |d - focus|), convolved with that core;
// - a halo (veiling glare): a share of the light spread by a wide round Gaussian.
// Each pixel integrates the image over its square. An elliptical core whose axes are turned away
// from the sensor's rows is not separable in x and y: its Gaussian is written as N(dy; Syy) times
// N(dx - c dy; Sxx - c^2 Syy), c = Sxy / Syy (a sheared Gaussian), so each strip's chord stays in
// closed form across the row and only the pixel's height is integrated numerically (Gauss-Legendre,
// the integrand analytic). The disc is a quadrature of shifted copies of the strips (rings of
// equal width, points 0.8 of the core's sd apart: their sum is the disc convolved with the core to
// far below the noise).

#include <vector>

#include <opencv2/core.hpp>

#include "sim/disc_image.h"

namespace irdist::sim {

// The Airy pattern's third dark ring over its first: J1's zeros x = 10.1735 and 3.8317.
constexpr double kAiryFirstZeroX = 3.8317;
constexpr double kAiryReachZeros = 10.1735 / kAiryFirstZeroX;

struct LensPsf {
  // The core Gaussian's covariance (px^2), the round defocus included when it is a Gaussian.
  double sxx_px2 = 0.0, sxy_px2 = 0.0, syy_px2 = 0.0;
  double disc_radius_px = 0.0;  // the geometric defocus disc's radius (0: none)
  // A diffraction-limited lens's Airy pattern: its first dark ring's radius (0: none), the pattern
  // out to its third dark ring (kAiryReachZeros), convolved with the core.
  double airy_first_zero_px = 0.0;
  double halo_share = 0.0;      // the share of the light in the halo
  double halo_sigma_px = 0.0;   // its round Gaussian's sd
  // The pixel's sensitive square, a share of the pitch per side (1: the whole pixel), centred
  // (sim/disc_image.h PixelResponse).
  double pixel_aperture = 1.0;
  // How far (px) the core and the disc reach beyond the image's edge: 4 sd of the core's wider
  // axis plus the disc's radius.
  double CoreReachPx() const;
  // The same for the halo (4 sd), 0 without one.
  double HaloReachPx() const;
};

namespace disc_image {

// Sums, per pixel of `out`, the strips blurred by the core and the disc of `psf` (not its halo)
// and integrated over the pixel's square, times `scale`.
void IntegrateStripsCore(const std::vector<ImageStrip>& strips, const LensPsf& psf, double scale,
                         const cv::Rect& rect, cv::Mat1f* out);

// The offsets (px) and weights (summing to 1) of the quadrature of a uniform disc of `radius_px`
// whose points lie at most `spacing_px` apart; one point at the centre for radius 0.
struct DiscPoint {
  double dx, dy, weight;
};
std::vector<DiscPoint> DiscQuadrature(double radius_px, double spacing_px);

// The Airy pattern I(r) = (2 J1(x) / x)^2, x = 3.8317 r / first_zero_px (J1's first zero), cut at
// its third dark ring (kAiryReachZeros x the first, 94% of its energy) and normalised there: a
// point at the centre (the innermost disc of the rings' width) and rings of equal width at most
// `ring_width_px`, each weighted by the pattern's energy in it (its encircled energy 1 - J0(x)^2 -
// J1(x)^2) and lying on the radius of its own mean r^2 under the pattern, its points at most
// `spacing_px` apart.
std::vector<DiscPoint> AiryQuadrature(double first_zero_px, double ring_width_px,
                                      double spacing_px);

}  // namespace disc_image
}  // namespace irdist::sim
