#include "sim/lens_psf.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "base/pi.h"

namespace irdist::sim {

double LensPsf::CoreReachPx() const {
  const double mean = 0.5 * (sxx_px2 + syy_px2);
  const double half_diff = std::hypot(0.5 * (sxx_px2 - syy_px2), sxy_px2);
  return 4.0 * std::sqrt(std::max(0.0, mean + half_diff)) + disc_radius_px +
         kAiryReachZeros * airy_first_zero_px;
}

double LensPsf::HaloReachPx() const { return halo_share > 0.0 ? 4.0 * halo_sigma_px : 0.0; }

namespace disc_image {
namespace {

// The Airy pattern's encircled energy within x = 3.8317 r / r0, and its intensity's mean r^2
// (in x^2) over [x0, x1] by Simpson's rule on 16 intervals (I(x) = (2 J1(x) / x)^2, weight x).
double AiryEnergy(double x) {
  if (!(x > 0.0)) return 0.0;
  const double j0 = std::cyl_bessel_j(0.0, x), j1 = std::cyl_bessel_j(1.0, x);
  return 1.0 - j0 * j0 - j1 * j1;
}
double AiryMeanX2(double x0, double x1) {
  double sum = 0.0, sum_x2 = 0.0;
  for (int i = 0; i <= 16; ++i) {
    const double x = x0 + (x1 - x0) * i / 16.0;
    const double j = x > 1e-9 ? 2.0 * std::cyl_bessel_j(1.0, x) / x : 1.0;
    const double w = (i == 0 || i == 16 ? 1.0 : (i % 2 == 1 ? 4.0 : 2.0)) * j * j * x;
    sum += w;
    sum_x2 += w * x * x;
  }
  return sum > 0.0 ? sum_x2 / sum : 0.5 * (x0 * x0 + x1 * x1);
}

// The quadrature of a round density out to `reach_px`: a point at the centre holding the share of
// the innermost disc (half a ring's width), then rings of equal width at most `ring_width_px`,
// ring [inner, outer] on the radius `radius_of(inner, outer)` holding `share_of(inner, outer)`,
// its points evenly spaced at most `spacing_px` apart (at least 3), neighbouring rings staggered.
template <typename Radius, typename Share>
std::vector<DiscPoint> RingQuadrature(double reach_px, double ring_width_px, double spacing_px,
                                      Radius radius_of, Share share_of) {
  const int rings = std::max(1, static_cast<int>(std::ceil(reach_px / ring_width_px)));
  const double width = reach_px / (rings + 0.5);
  std::vector<DiscPoint> points = {{0.0, 0.0, share_of(0.0, 0.5 * width)}};
  for (int i = 1; i <= rings; ++i) {
    const double inner = (i - 0.5) * width, outer = (i + 0.5) * width;
    const double mid = radius_of(inner, outer);
    const int count = std::max(3, static_cast<int>(std::ceil(2.0 * kPi * mid / spacing_px)));
    const double weight = share_of(inner, outer) / count;
    const double turn = (i % 2 == 0) ? 0.5 : 0.0;
    for (int k = 0; k < count; ++k) {
      const double a = 2.0 * kPi * (k + turn) / count;
      points.push_back({mid * std::cos(a), mid * std::sin(a), weight});
    }
  }
  return points;
}

}  // namespace

std::vector<DiscPoint> DiscQuadrature(double radius_px, double spacing_px) {
  if (!(radius_px > 0.0)) return {{0.0, 0.0, 1.0}};
  // Each ring on the radius of its own mean r^2 (the disc's second moment kept), each point
  // weighted by its share of the area.
  const double total = radius_px * radius_px;
  return RingQuadrature(
      radius_px, spacing_px, spacing_px,
      [](double inner, double outer) { return std::sqrt(0.5 * (inner * inner + outer * outer)); },
      [total](double inner, double outer) { return (outer * outer - inner * inner) / total; });
}

std::vector<DiscPoint> AiryQuadrature(double first_zero_px, double ring_width_px,
                                      double spacing_px) {
  const double to_x = kAiryFirstZeroX / first_zero_px;
  const double reach = kAiryReachZeros * first_zero_px;
  const double total = AiryEnergy(reach * to_x);
  return RingQuadrature(
      reach, ring_width_px, spacing_px,
      [to_x](double inner, double outer) {
        return std::sqrt(AiryMeanX2(inner * to_x, outer * to_x)) / to_x;
      },
      [to_x, total](double inner, double outer) {
        return (AiryEnergy(outer * to_x) - AiryEnergy(inner * to_x)) / total;
      });
}

namespace {

// The quadrature of the core's spread beyond its Gaussian: the defocus disc's or the Airy
// pattern's points; one point at the centre without either.
std::vector<DiscPoint> SpreadPoints(const LensPsf& psf) {
  // The points at most 0.8 of the core's narrower sd apart: the sum of the shifted cores is then
  // the disc convolved with the core to far below the noise (the error falls as
  // exp(-2 pi^2 sd^2 / spacing^2) inside the disc, 4e-14 here), at a cost the virtual camera
  // keeps up with (each point a copy of the strips). The Airy pattern's rings and their points
  // lie 1.2 sd apart (radially and along each ring): each ring's light lumped on one radius, the
  // blurred pattern is within 0.3% of its peak of the converged one (lens_psf_test; a
  // second-order quadrature, 0.1% at 0.2 sd for 5x the points): the rig's lens is that sum of
  // shifted cores, the same in every render, truth and bound alike.
  const double mean = 0.5 * (psf.sxx_px2 + psf.syy_px2);
  const double half_diff = std::hypot(0.5 * (psf.sxx_px2 - psf.syy_px2), psf.sxy_px2);
  const double narrow_sd = std::sqrt(std::max(1e-4, mean - half_diff));
  if (psf.disc_radius_px > 0.0) return DiscQuadrature(psf.disc_radius_px, 0.8 * narrow_sd);
  if (psf.airy_first_zero_px > 0.0) {
    return AiryQuadrature(psf.airy_first_zero_px, 1.2 * narrow_sd, 1.2 * narrow_sd);
  }
  return {{0.0, 0.0, 1.0}};
}

// The strips shifted to every point of the PSF's spread (SpreadPoints), each weighted by its point.
std::vector<ImageStrip> SpreadOverPoints(const std::vector<ImageStrip>& strips,
                                         const LensPsf& psf) {
  if (!(psf.disc_radius_px > 0.0) && !(psf.airy_first_zero_px > 0.0)) return strips;
  const std::vector<DiscPoint> points = SpreadPoints(psf);
  std::vector<ImageStrip> out;
  out.reserve(strips.size() * points.size());
  for (const DiscPoint& p : points) {
    for (const ImageStrip& s : strips) {
      out.push_back({s.y_px + p.dy, s.weight_px * p.weight, s.left_px + p.dx, s.right_px + p.dx,
                     s.radiance});
    }
  }
  return out;
}

// The strips through a sheared Gaussian, N(dy; syy) N(dx - c dy; v): at each Gauss-Legendre node
// y across a pixel's row, strip k's chord [l, r] blurred in x lies at [l + c dy, r + c dy], dy =
// y - y_k, and the pixel's width integrates it in closed form (PixelResponse::H).
void IntegrateSheared(const std::vector<ImageStrip>& strips, const LensPsf& psf, double scale,
                      const cv::Rect& rect, cv::Mat1f* out) {
  const double sy = std::sqrt(psf.syy_px2);
  const double shear = psf.sxy_px2 / psf.syy_px2;
  const PixelResponse chord(std::sqrt(std::max(1e-12, psf.sxx_px2 - shear * psf.sxy_px2)),
                            psf.pixel_aperture);
  // The row factor is a Gaussian of sd sy over a width of one pixel: analytic, so the quadrature
  // converges fast; more nodes for a narrow one. The nodes span the pixel's sensitive height, and
  // their mean is taken (the aperture's response divided by its width, as PixelResponse's).
  const int nodes = std::clamp(static_cast<int>(std::ceil(6.0 / sy)), 8, 48);
  std::vector<double> x, w;
  GaussLegendre(nodes, &x, &w);
  const double norm = 1.0 / (std::sqrt(2.0 * kPi) * sy);
  std::vector<double> row(rect.width);
  for (int r = 0; r < rect.height; ++r) {
    std::fill(row.begin(), row.end(), 0.0);
    const double y_pixel = rect.y + r + 0.5;
    for (int j = 0; j < nodes; ++j) {
      const double y = y_pixel + 0.5 * psf.pixel_aperture * x[j];
      for (const ImageStrip& s : strips) {
        const double dy = y - s.y_px;
        if (std::fabs(dy) > 8.0 * sy) continue;
        const double g = 0.5 * w[j] * s.weight_px * s.radiance * norm *
                         std::exp(-0.5 * dy * dy / psf.syy_px2);
        const double left = s.left_px + shear * dy - rect.x - 0.5;
        const double right = s.right_px + shear * dy - rect.x - 0.5;
        for (int col = 0; col < rect.width; ++col) {
          row[col] += g * (chord.H(right - col) - chord.H(left - col));
        }
      }
    }
    float* dst = (*out)[r];
    for (int col = 0; col < rect.width; ++col) dst[col] += static_cast<float>(row[col] * scale);
  }
}

}  // namespace

void IntegrateStripsCore(const std::vector<ImageStrip>& strips, const LensPsf& psf, double scale,
                         const cv::Rect& rect, cv::Mat1f* out) {
  const std::vector<ImageStrip> spread = SpreadOverPoints(strips, psf);
  // Turned axes couple x and y; axes along the rows (or a round core) keep the separable sum.
  if (std::fabs(psf.sxy_px2) > 1e-9 * (psf.sxx_px2 + psf.syy_px2)) {
    IntegrateSheared(spread, psf, scale, rect, out);
    return;
  }
  IntegrateStrips(spread, PixelResponse(std::sqrt(psf.syy_px2), psf.pixel_aperture),
                  PixelResponse(std::sqrt(psf.sxx_px2), psf.pixel_aperture), scale, rect, out);
}

}  // namespace disc_image
}  // namespace irdist::sim
