#pragma once
// An independent renderer of bench scenes for the scene pass's tests and bench (not the
// estimator's model, not the virtual rig's): uniformly bright elliptical discs, optionally cut by
// a straight occluder, supersampled 16 x 16 per pixel, blurred by a Gaussian (cv::GaussianBlur
// on the fine grid), area-averaged onto the pixels; then a Mono12 sensor with an EMVA-like noise
// (shot noise through K = 0.39 DN/e-, 7 e- read noise, 16 DN black level), quantised.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

namespace irdist::testing {

constexpr double kScenePi = 3.14159265358979323846;

struct SceneDisc {
  double cx = 0.0, cy = 0.0;  // pixel centres at integers
  double a = 8.0, b = 8.0;    // semi-axes, px
  double angle_deg = 0.0;     // of the a axis
  double amplitude_e = 5000.0;
  double cut = 0.0;           // share of the disc's area a straight occluder removes
  double cut_angle_deg = 0.0; // direction of the occluder's normal (towards the removed part)
  // A cable: a dark straight band of band_px width (0: none) across the disc, its centre line
  // band_offset_px from the disc's centre, its normal at cut_angle_deg.
  double band_px = 0.0;
  double band_offset_px = 0.0;
};

// h in [-1, 1] such that the unit disc's segment beyond the line at distance h has area `cut`.
inline double ChordForCut(double cut) {
  double lo = -1.0, hi = 1.0;
  for (int i = 0; i < 60; ++i) {
    const double h = 0.5 * (lo + hi);
    const double seg = (std::acos(h) - h * std::sqrt(1.0 - h * h)) / kScenePi;
    (seg > cut ? lo : hi) = h;
  }
  return 0.5 * (lo + hi);
}

// Adds one disc (electrons) onto `electrons` (CV_64F) with the blur `blur_px`.
inline void AddDisc(const SceneDisc& d, double blur_px, cv::Mat1d* electrons) {
  constexpr int kSuper = 16;
  const int half = static_cast<int>(std::ceil(std::max(d.a, d.b) + 5.0 * blur_px + 3.0));
  const int x0 = static_cast<int>(std::floor(d.cx)) - half, y0 = static_cast<int>(std::floor(d.cy)) - half;
  const int side = 2 * half + 1;
  cv::Mat1f fine(side * kSuper, side * kSuper, 0.0f);
  const double c = std::cos(d.angle_deg * kScenePi / 180.0), s = std::sin(d.angle_deg * kScenePi / 180.0);
  const double h = d.cut > 0.0 ? ChordForCut(d.cut) : 2.0;
  const double nc = std::cos(d.cut_angle_deg * kScenePi / 180.0), ns = std::sin(d.cut_angle_deg * kScenePi / 180.0);
  for (int row = 0; row < fine.rows; ++row) {
    for (int col = 0; col < fine.cols; ++col) {
      const double x = x0 + (col + 0.5) / kSuper - 0.5 - d.cx, y = y0 + (row + 0.5) / kSuper - 0.5 - d.cy;
      const double u = (c * x + s * y) / d.a, v = (-s * x + c * y) / d.b;
      const bool cable = std::abs(nc * x + ns * y - d.band_offset_px) < 0.5 * d.band_px;
      if (u * u + v * v <= 1.0 && nc * u + ns * v <= h && !cable) fine(row, col) = 1.0f;
    }
  }
  cv::GaussianBlur(fine, fine, cv::Size(0, 0), blur_px * kSuper);
  cv::Mat1f coarse;
  cv::resize(fine, coarse, cv::Size(side, side), 0, 0, cv::INTER_AREA);
  for (int row = 0; row < side; ++row) {
    for (int col = 0; col < side; ++col) {
      const int y = y0 + row, x = x0 + col;
      if (x >= 0 && y >= 0 && x < electrons->cols && y < electrons->rows)
        (*electrons)(y, x) += d.amplitude_e * coarse(row, col);
    }
  }
}

inline cv::Mat1d RenderScene(int side, double background_e, const std::vector<SceneDisc>& discs,
                             double blur_px) {
  cv::Mat1d electrons(side, side, background_e);
  for (const SceneDisc& d : discs) AddDisc(d, blur_px, &electrons);
  return electrons;
}

// A standard normal field (the same draws give the same noise to two scenes).
inline cv::Mat1d NormalField(int side, std::mt19937_64* rng) {
  cv::Mat1d z(side, side);
  std::normal_distribution<double> unit(0.0, 1.0);
  for (double& v : z) v = unit(*rng);
  return z;
}

// Electrons -> Mono12 (K 0.39 DN/e-, black 16 DN, shot + 7 e- read noise from the field z, none
// when z is empty).
inline cv::Mat SensorFrame(const cv::Mat1d& electrons, const cv::Mat1d& z) {
  cv::Mat out(electrons.size(), CV_16UC1);
  for (int row = 0; row < out.rows; ++row) {
    for (int col = 0; col < out.cols; ++col) {
      double e = electrons(row, col);
      if (!z.empty()) e += std::sqrt(e + 49.0) * z(row, col);
      out.at<std::uint16_t>(row, col) =
          static_cast<std::uint16_t>(std::clamp(std::round(0.39 * e + 16.0), 0.0, 4095.0));
    }
  }
  return out;
}

}  // namespace irdist::testing
