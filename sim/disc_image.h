#pragma once
// sim-internal (included by sim/*.cc only): the exact image of a uniformly bright circular disc,
// optionally cut by a straight edge in its own plane, as the Scene renders it. The disc's
// perspective image is a conic; it is cut into horizontal strips (each a chord of the conic, or of
// the conic and the edge's image, a straight line), and each pixel sums the strips' responses to
// the Gaussian blur convolved with its own square, in closed form (sim/scene.h).

#include <algorithm>
#include <cmath>
#include <vector>

#include <opencv2/core.hpp>

#include "base/pi.h"

namespace irdist::sim {

// One horizontal strip of the disc's image: its y (px), weight (px), chord ends (px), radiance.
struct ImageStrip {
  double y_px, weight_px, left_px, right_px, radiance;
};

namespace disc_image {

struct Vec3 {
  double x, y, z;
};
inline double Dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

// The disc's image in the image plane (mm): the ray (u, v, f) meets the disc's plane at
// t (u, v, f), t = nc / n.ray; it lands inside the disc iff |nc ray - (n.ray) c|^2 <= R^2 (n.ray)^2.
// With ray = (0, v, f) + u e_x this is A u^2 + 2 B(v) u + C(v) <= 0, B linear and C quadratic in v.
struct DiscConic {
  double qa = 0.0, b0 = 0.0, b1 = 0.0, c0 = 0.0, c1 = 0.0, c2 = 0.0;
  double v_mid = 0.0, v_half = 0.0;  // the chord exists for |v - v_mid| <= v_half
  bool in_view = false;
  // Chord ends (mm) at height v.
  void Chord(double v, double* u_left, double* u_right) const;
  // The conic's value at (u, v): <= 0 inside the disc's image.
  double Value(double u, double v) const;
};

// The conic of the disc of centre c, unit normal n and squared radius radius2 (mm), focal length f.
DiscConic MakeDiscConic(const Vec3& n, const Vec3& c, double radius2, double f);

// The image (mm) of a straight edge over the disc: the visible part of the image plane is
// a_u u + a_v v + a_0 > 0 (the rest is covered).
struct ImageCut {
  double a_u = 0.0, a_v = 0.0, a_0 = 0.0;
  // Clips the chord [u_left, u_right] at height v to its visible part (u_left > u_right: none).
  void Clip(double v, double* u_left, double* u_right) const;
};

// The edge where (p - c) . w = offset_mm on the disc's plane (c centre, n normal, w a unit vector
// in the plane), covered on the side where (p - c) . w > offset_mm, seen through the pinhole.
ImageCut MakeImageCut(const Vec3& n, const Vec3& c, const Vec3& w, double offset_mm, double f);

// A range of v (mm), as centre and half-height, over which the visible chord is a smooth function.
struct StripRange {
  double v_mid, v_half;
};

// The ranges of v where the cut disc's image has a visible chord, split where the edge meets the
// conic (the chord's ends have kinks there): each range's strips then converge as fast as the
// uncut disc's.
std::vector<StripRange> VisibleRanges(const DiscConic& conic, const ImageCut& cut);

// Gauss-Legendre nodes and weights of order n on [-1, 1] (exact for polynomials of degree 2n - 1).
void GaussLegendre(int n, std::vector<double>* nodes, std::vector<double>* weights);

// The pixel's response to a Gaussian blur of `sigma` px: h(x) = PSF convolved with the pixel's
// sensitive box, and H(x) its integral from -infinity (closed forms with Phi and phi). The box is
// `aperture` of the pitch wide (1: the whole pixel; a fill factor below it), centred on the
// pixel, and its response is divided by its width: a flat field gives every aperture the same
// signal (a datasheet's quantum efficiency is the whole pixel's, its fill factor included).
class PixelResponse {
 public:
  explicit PixelResponse(double sigma, double aperture = 1.0)
      : sigma_(sigma), half_(0.5 * aperture), reach_(half_ + 8.0 * std::max(sigma, 1e-9)) {}
  double h(double x) const {
    return std::fabs(x) >= reach_ ? 0.0 : (Step(x + half_) - Step(x - half_)) / (2.0 * half_);
  }
  double H(double x) const {
    if (x >= reach_) return 1.0;
    if (x <= -reach_) return 0.0;
    return (Psi(x + half_) - Psi(x - half_)) / (2.0 * half_);
  }

 private:
  double Psi(double z) const {  // integral of the PSF's step response: z Phi(z) + sigma phi(z)
    if (sigma_ <= 1e-9) return std::max(z, 0.0);
    const double t = z / sigma_;
    if (t < -8.0) return 0.0;
    if (t > 8.0) return z;
    return z * 0.5 * std::erfc(-t / std::sqrt(2.0)) +
           sigma_ * std::exp(-0.5 * t * t) / std::sqrt(2.0 * kPi);
  }
  double Step(double z) const {  // Phi(z / sigma)
    if (sigma_ <= 1e-9) return z >= 0.0 ? 1.0 : 0.0;
    return 0.5 * std::erfc(-z / (sigma_ * std::sqrt(2.0)));
  }
  double sigma_, half_, reach_;
};

// Sums, per pixel of `out`, the strips weighted by h(row) (row_response: the blur along y) and H
// across each chord (chord_response: along x), times `scale`, added to `out`.
void IntegrateStrips(const std::vector<ImageStrip>& strips, const PixelResponse& row_response,
                     const PixelResponse& chord_response, double scale, const cv::Rect& rect,
                     cv::Mat1f* out);

}  // namespace disc_image
}  // namespace irdist::sim
