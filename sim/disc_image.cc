#include "sim/disc_image.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace irdist::sim::disc_image {

void DiscConic::Chord(double v, double* u_left, double* u_right) const {
  const double b = b0 + b1 * v;
  const double d = std::max(0.0, b * b - qa * (c0 + 2.0 * c1 * v + c2 * v * v));
  *u_left = (-b - std::sqrt(d)) / qa;
  *u_right = (-b + std::sqrt(d)) / qa;
}

double DiscConic::Value(double u, double v) const {
  return qa * u * u + 2.0 * (b0 + b1 * v) * u + c0 + 2.0 * c1 * v + c2 * v * v;
}

DiscConic MakeDiscConic(const Vec3& n, const Vec3& c, double radius2, double f) {
  DiscConic k;
  const double nc = Dot(n, c);
  const Vec3 w1 = {nc - n.x * c.x, -n.x * c.y, -n.x * c.z};  // nc e_x - n_x c
  const Vec3 a0 = {-n.z * f * c.x, -n.z * f * c.y, nc * f - n.z * f * c.z};  // w0 at v = 0
  const Vec3 a1 = {-n.y * c.x, nc - n.y * c.y, -n.y * c.z};                  // dw0/dv
  const double m0 = n.z * f, m1 = n.y;                                        // n.ray at u = 0
  k.qa = Dot(w1, w1) - radius2 * n.x * n.x;
  k.b0 = Dot(a0, w1) - radius2 * m0 * n.x;
  k.b1 = Dot(a1, w1) - radius2 * m1 * n.x;
  k.c0 = Dot(a0, a0) - radius2 * m0 * m0;
  k.c1 = Dot(a0, a1) - radius2 * m0 * m1;
  k.c2 = Dot(a1, a1) - radius2 * m1 * m1;
  // The chord exists where B^2 - A C >= 0: a quadratic in v, negative outside [v_lo, v_hi].
  const double d2 = k.b1 * k.b1 - k.qa * k.c2, d1 = k.b0 * k.b1 - k.qa * k.c1;
  const double d0 = k.b0 * k.b0 - k.qa * k.c0;
  const double disc_v = d1 * d1 - d2 * d0;
  k.in_view = k.qa > 0.0 && d2 < 0.0 && disc_v > 0.0;
  if (k.in_view) {
    k.v_mid = -d1 / d2;
    k.v_half = std::fabs(std::sqrt(disc_v) / d2);
  }
  return k;
}

void ImageCut::Clip(double v, double* u_left, double* u_right) const {
  const double rest = a_v * v + a_0;
  if (a_u == 0.0) {  // an edge along the image's rows: the chord is all visible or all covered
    if (rest <= 0.0) *u_right = *u_left - 1.0;
    return;
  }
  const double u_edge = -rest / a_u;
  if (a_u > 0.0) {
    *u_left = std::max(*u_left, u_edge);
  } else {
    *u_right = std::min(*u_right, u_edge);
  }
}

ImageCut MakeImageCut(const Vec3& n, const Vec3& c, const Vec3& w, double offset_mm, double f) {
  // The ray r = (u, v, f) meets the plane at s r, s = nc / n.r > 0 (the disc is in front); that
  // point is covered iff s r.w - (c.w + offset) >= 0, i.e. iff g = nc r.w - k n.r has the sign of
  // nc (that of n.r). g is linear in (u, v): the edge's image is a straight line.
  const double nc = Dot(n, c);
  const double k = Dot(c, w) + offset_mm;
  const double visible_sign = nc > 0.0 ? -1.0 : 1.0;
  ImageCut cut;
  cut.a_u = visible_sign * (nc * w.x - k * n.x);
  cut.a_v = visible_sign * (nc * w.y - k * n.y);
  cut.a_0 = visible_sign * f * (nc * w.z - k * n.z);
  return cut;
}

namespace {

// The v (mm) of the points where the line a_u u + a_v v + a_0 = 0 meets the conic, if it does.
std::vector<double> EdgeMeetsConic(const DiscConic& k, const ImageCut& cut) {
  const double norm2 = cut.a_u * cut.a_u + cut.a_v * cut.a_v;
  if (norm2 <= 0.0) return {};
  const double pu = -cut.a_0 * cut.a_u / norm2, pv = -cut.a_0 * cut.a_v / norm2;
  const double du = -cut.a_v, dv = cut.a_u;  // the line: (pu, pv) + s (du, dv)
  const double a = k.qa * du * du + 2.0 * k.b1 * du * dv + k.c2 * dv * dv;
  const double b = k.qa * pu * du + k.b0 * du + k.b1 * (pu * dv + pv * du) + k.c1 * dv +
                   k.c2 * pv * dv;
  const double c = k.Value(pu, pv);
  const double disc = b * b - a * c;
  if (a == 0.0 || disc <= 0.0) return {};
  const double root = std::sqrt(disc);
  return {pv + (-b - root) / a * dv, pv + (-b + root) / a * dv};
}

}  // namespace

std::vector<StripRange> VisibleRanges(const DiscConic& conic, const ImageCut& cut) {
  const double v_lo = conic.v_mid - conic.v_half, v_hi = conic.v_mid + conic.v_half;
  std::vector<double> bounds = {v_lo, v_hi};
  for (double v : EdgeMeetsConic(conic, cut)) {
    if (v > v_lo && v < v_hi) bounds.push_back(v);
  }
  std::sort(bounds.begin(), bounds.end());
  std::vector<StripRange> ranges;
  for (size_t i = 0; i + 1 < bounds.size(); ++i) {
    const double half = 0.5 * (bounds[i + 1] - bounds[i]);
    if (half <= 1e-12 * conic.v_half) continue;
    const double mid = 0.5 * (bounds[i] + bounds[i + 1]);
    double u_left = 0.0, u_right = 0.0;
    conic.Chord(mid, &u_left, &u_right);
    cut.Clip(mid, &u_left, &u_right);
    if (u_right > u_left) ranges.push_back({mid, half});
  }
  return ranges;
}

void GaussLegendre(int n, std::vector<double>* nodes, std::vector<double>* weights) {
  nodes->assign(n, 0.0);
  weights->assign(n, 0.0);
  for (int i = 0; i < (n + 1) / 2; ++i) {
    double x = std::cos(kPi * (i + 0.75) / (n + 0.5));  // Newton from Tricomi's guess
    double dp = 1.0;
    for (int iteration = 0; iteration < 100; ++iteration) {
      double p0 = 1.0, p1 = 0.0;
      for (int j = 1; j <= n; ++j) {  // P_j(x) by the three-term recurrence
        const double p2 = p1;
        p1 = p0;
        p0 = ((2.0 * j - 1.0) * x * p1 - (j - 1.0) * p2) / j;
      }
      dp = n * (x * p0 - p1) / (x * x - 1.0);
      const double step = p0 / dp;
      x -= step;
      if (std::fabs(step) < 1e-15) break;
    }
    (*nodes)[i] = -x;
    (*nodes)[n - 1 - i] = x;
    (*weights)[i] = (*weights)[n - 1 - i] = 2.0 / ((1.0 - x * x) * dp * dp);
  }
}

void IntegrateStrips(const std::vector<ImageStrip>& strips, const PixelResponse& row_response,
                     const PixelResponse& chord_response, double scale, const cv::Rect& rect,
                     cv::Mat1f* out) {
  const int rows = rect.height, cols = rect.width;
  const int count = static_cast<int>(strips.size());
  std::vector<double> row_weight(static_cast<size_t>(rows) * count);
  std::vector<double> chord(static_cast<size_t>(count) * cols);
  for (int r = 0; r < rows; ++r) {
    const double y = rect.y + r + 0.5;
    for (int k = 0; k < count; ++k) {
      const ImageStrip& st = strips[k];
      row_weight[static_cast<size_t>(r) * count + k] =
          st.weight_px * st.radiance * row_response.h(st.y_px - y);
    }
  }
  for (int k = 0; k < count; ++k) {
    for (int col = 0; col < cols; ++col) {
      const double x = rect.x + col + 0.5;
      chord[static_cast<size_t>(k) * cols + col] =
          chord_response.H(strips[k].right_px - x) - chord_response.H(strips[k].left_px - x);
    }
  }
  for (int r = 0; r < rows; ++r) {
    float* dst = (*out)[r];
    const double* wr = &row_weight[static_cast<size_t>(r) * count];
    for (int col = 0; col < cols; ++col) {
      double sum = 0.0;
      for (int k = 0; k < count; ++k) sum += wr[k] * chord[static_cast<size_t>(k) * cols + col];
      dst[col] += static_cast<float>(sum * scale);
    }
  }
}

}  // namespace irdist::sim::disc_image
