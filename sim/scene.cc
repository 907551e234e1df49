#include "sim/scene.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <opencv2/imgproc.hpp>

namespace irdist::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;
constexpr double kPlanck = 6.62607015e-34;  // J s
constexpr double kLightSpeed = 2.99792458e8;  // m/s

struct Vec3 {
  double x, y, z;
};
double Dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

Vec3 EmissionAxis(const PoseState& pose) {
  const double p = pose.pan_deg * kDeg;
  const double t = pose.tilt_deg * kDeg;
  return {std::sin(p) * std::cos(t), std::sin(t), -std::cos(p) * std::cos(t)};
}

}  // namespace

Scene::Scene(const RigPhysics& physics) : physics_(physics) {
  std::string why;
  IRDIST_CHECK(physics_.IsValid(&why), why);
  const OpticsOptions& o = physics_.optics;
  const SensorOptions& s = physics_.sensor;
  const double pixel_area_m2 = std::pow(s.pixel_pitch_um * 1e-6, 2);
  const double photon_j = kPlanck * kLightSpeed / (physics_.emitter.wavelength_nm * 1e-9);
  // Camera equation: E = L * tau * pi / (4 N^2) on the axis (object far beyond the focal length).
  electrons_per_radiance_s_ = s.quantum_efficiency * o.lens_transmission * o.filter_transmission *
                              kPi / (4.0 * o.f_number * o.f_number) * pixel_area_m2 / photon_j;
}

double Scene::JunctionRiseK(const std::vector<CurrentStep>& history, double t_s) const {
  const EmitterOptions& e = physics_.emitter;
  double rise = 0.0;
  double current_ma = 0.0;
  double time = 0.0;
  auto advance = [&](double until) {
    const double dt = until - time;
    if (dt <= 0.0) return;
    const double steady = e.thermal_resistance_k_per_w * current_ma * 1e-3 * e.forward_voltage_v;
    rise = steady + (rise - steady) * std::exp(-dt / e.thermal_time_constant_s);
    time = until;
  };
  for (const CurrentStep& step : history) {
    if (step.sim_time_s > t_s) break;
    advance(step.sim_time_s);
    current_ma = step.bias_ma;
  }
  advance(t_s);
  return rise;
}

double Scene::OnAxisIntensityMwSr(double bias_ma, double junction_rise_k) const {
  const EmitterOptions& e = physics_.emitter;
  const double above = bias_ma - e.threshold_ma;
  if (above <= 0.0) return 0.0;
  const double droop = std::max(0.0, 1.0 - e.sublinear_per_ma * above);
  const double thermal = std::max(0.0, 1.0 + e.temp_coeff_per_k * junction_rise_k);
  return e.slope_mw_sr_per_ma * above * droop * thermal;
}

double Scene::Pattern(double angle_rad) const {
  const EmitterOptions& e = physics_.emitter;
  switch (e.pattern) {
    case EmissionPattern::kGaussian: {
      const double sigma = e.pattern_sigma_deg * kDeg;
      return std::exp(-angle_rad * angle_rad / (2.0 * sigma * sigma));
    }
    case EmissionPattern::kCosPower: {
      const double c = std::cos(angle_rad);
      return c > 0.0 ? std::pow(c, e.pattern_cos_power) : 0.0;
    }
  }
  return 0.0;
}

EmitterImage Scene::Project(const PoseState& pose) const {
  const EmitterOptions& e = physics_.emitter;
  const SensorOptions& s = physics_.sensor;
  const double f = physics_.optics.focal_length_mm;
  const double pitch_mm = s.pixel_pitch_um * 1e-3;
  EmitterImage image;
  const double d = std::max(pose.slide_mm, 1.0);
  image.center_x_px = 0.5 * s.width_px + f * e.offset_x_mm / d / pitch_mm;
  image.center_y_px = 0.5 * s.height_px + f * e.offset_y_mm / d / pitch_mm;
  const Vec3 n = EmissionAxis(pose);
  const Vec3 to_camera = {-e.offset_x_mm, -e.offset_y_mm, -d};
  const double cos_theta = Dot(n, to_camera) / std::sqrt(Dot(to_camera, to_camera));
  image.theta_deg = std::acos(std::clamp(cos_theta, -1.0, 1.0)) / kDeg;
  const double dist = std::sqrt(Dot(to_camera, to_camera));
  image.major_px = e.diameter_mm * f / dist / pitch_mm;
  image.minor_px = image.major_px * std::fabs(cos_theta);
  return image;
}

SignalWindow Scene::RenderSignal(const PoseState& pose, double intensity_mw_sr,
                                 double exposure_s) const {
  const EmitterOptions& e = physics_.emitter;
  const OpticsOptions& o = physics_.optics;
  const SensorOptions& s = physics_.sensor;
  const EmitterImage image = Project(pose);
  const double psf = o.psf_sigma_px;
  const double half = 0.5 * image.major_px * 1.05 + 4.0 * psf + 2.0;
  const cv::Rect wanted(static_cast<int>(std::floor(image.center_x_px - half)),
                        static_cast<int>(std::floor(image.center_y_px - half)),
                        static_cast<int>(std::ceil(2 * half)) + 1,
                        static_cast<int>(std::ceil(2 * half)) + 1);
  SignalWindow out;
  out.rect = wanted & cv::Rect(0, 0, s.width_px, s.height_px);
  if (out.rect.empty()) return out;
  out.electrons = cv::Mat1f::zeros(out.rect.height, out.rect.width);
  if (intensity_mw_sr <= 0.0 || exposure_s <= 0.0) return out;

  // The pixel value is the disc's image (radiance x camera equation) convolved with the Gaussian
  // PSF and integrated over the pixel's square, evaluated exactly: the pixel's response to a
  // point is separable, h(x) h(y) with h = PSF convolved with the pixel's width, so a pixel sums,
  // over thin horizontal strips of the disc's image, h(strip y - pixel y) times the integral of
  // h across the strip's chord (closed form). The strips are Chebyshev-spaced in y (nodes at
  // y = centre + half-height * sin(phi), phi evenly spaced), which makes the chord's square-root
  // ends smooth, so the sum converges fast. Radiance is taken at each chord's midpoint (it
  // varies by < 0.5 % across the disc, linearly to first order). No sampling of the sharp
  // disc happens anywhere, so nothing aliases: sampling a sharp edge on a grid and blurring
  // afterwards put a pose-dependent error of up to +-0.5 deg into the blob's shape.
  const double f = o.focal_length_mm;
  const double pitch_mm = s.pixel_pitch_um * 1e-3;
  const double cx = 0.5 * s.width_px;
  const double cy = 0.5 * s.height_px;
  const Vec3 n = EmissionAxis(pose);
  const Vec3 c = {e.offset_x_mm, e.offset_y_mm, pose.slide_mm};
  const double nc = Dot(n, c);
  const double radius2 = 0.25 * e.diameter_mm * e.diameter_mm;
  const double area_m2 = kPi * radius2 * 1e-6;
  const double intensity_w_sr = intensity_mw_sr * 1e-3;
  const double scale = electrons_per_radiance_s_ * exposure_s;

  // The ray (u, v, f) (image-plane mm) meets the disc's plane at t (u, v, f), t = nc / n.ray;
  // it lands inside the disc iff |nc ray - (n.ray) c|^2 <= R^2 (n.ray)^2. With
  // ray = (0, v, f) + u e_x this is A u^2 + 2 B(v) u + C(v) <= 0, B linear and C quadratic in v.
  const Vec3 w1 = {nc - n.x * c.x, -n.x * c.y, -n.x * c.z};  // nc e_x - n_x c
  const Vec3 a0 = {-n.z * f * c.x, -n.z * f * c.y, nc * f - n.z * f * c.z};  // w0 at v = 0
  const Vec3 a1 = {-n.y * c.x, nc - n.y * c.y, -n.y * c.z};                  // dw0/dv
  const double m0 = n.z * f, m1 = n.y;                                        // n.ray at u = 0
  const double qa = Dot(w1, w1) - radius2 * n.x * n.x;
  const double b0 = Dot(a0, w1) - radius2 * m0 * n.x, b1 = Dot(a1, w1) - radius2 * m1 * n.x;
  const double c0 = Dot(a0, a0) - radius2 * m0 * m0;
  const double c1 = Dot(a0, a1) - radius2 * m0 * m1;
  const double c2 = Dot(a1, a1) - radius2 * m1 * m1;
  // The chord exists where B^2 - A C >= 0: a quadratic in v, negative outside [v_lo, v_hi].
  const double d2 = b1 * b1 - qa * c2, d1 = b0 * b1 - qa * c1, d0 = b0 * b0 - qa * c0;
  const double disc_v = d1 * d1 - d2 * d0;
  if (!(qa > 0.0) || !(d2 < 0.0) || !(disc_v > 0.0)) return out;  // not an ellipse in view
  const double v_mid = -d1 / d2, v_half = std::fabs(std::sqrt(disc_v) / d2);

  // Strips: per node its y (px), weight (px), chord ends (px) and radiance.
  const double height_px = 2.0 * v_half / pitch_mm;
  const int nodes = std::max(32, static_cast<int>(std::ceil(o.supersample * height_px)));
  struct Strip {
    double y_px, weight_px, left_px, right_px, radiance;
  };
  std::vector<Strip> strips;
  strips.reserve(nodes);
  for (int k = 0; k < nodes; ++k) {
    const double phi = -0.5 * kPi + (k + 0.5) * kPi / nodes;
    const double v = v_mid + v_half * std::sin(phi);
    const double b = b0 + b1 * v;
    const double d = std::max(0.0, b * b - qa * (c0 + 2.0 * c1 * v + c2 * v * v));
    const double u_left = (-b - std::sqrt(d)) / qa, u_right = (-b + std::sqrt(d)) / qa;
    const double u = 0.5 * (u_left + u_right);
    const Vec3 ray = {u, v, f};
    const double n_ray = Dot(n, ray);
    if (std::fabs(n_ray) < 1e-12 || nc / n_ray <= 0.0) continue;
    const Vec3 p = {nc / n_ray * ray.x, nc / n_ray * ray.y, nc / n_ray * ray.z};
    // Radiance of the disc towards the pinhole: I(a) / (A cos a), a = emission angle.
    const double cos_a = -Dot(n, p) / std::sqrt(Dot(p, p));
    if (cos_a <= 1e-6) continue;
    double radiance =
        intensity_w_sr * Pattern(std::acos(std::min(1.0, cos_a))) / (area_m2 * cos_a);
    if (o.vignetting) {
      const double cos_field = f / std::sqrt(Dot(ray, ray));
      radiance *= cos_field * cos_field * cos_field * cos_field;
    }
    strips.push_back({v / pitch_mm + cy, v_half * std::cos(phi) * kPi / nodes / pitch_mm,
                      u_left / pitch_mm + cx, u_right / pitch_mm + cx, radiance});
  }

  // h(x) = PSF (sigma, px) convolved with the unit box, and H its integral from -infinity.
  const double sigma = psf;
  auto psi = [sigma](double z) {  // integral of the PSF's step response: z Phi(z) + sigma phi(z)
    if (sigma <= 1e-9) return std::max(z, 0.0);
    const double t = z / sigma;
    if (t < -8.0) return 0.0;
    if (t > 8.0) return z;
    return z * 0.5 * std::erfc(-t / std::sqrt(2.0)) +
           sigma * std::exp(-0.5 * t * t) / std::sqrt(2.0 * kPi);
  };
  auto step = [sigma](double z) {  // Phi(z / sigma)
    if (sigma <= 1e-9) return z >= 0.0 ? 1.0 : 0.0;
    return 0.5 * std::erfc(-z / (sigma * std::sqrt(2.0)));
  };
  const double reach = 0.5 + 8.0 * std::max(sigma, 1e-9);
  auto h = [&](double x) { return std::fabs(x) >= reach ? 0.0 : step(x + 0.5) - step(x - 0.5); };
  auto big_h = [&](double x) {
    if (x >= reach) return 1.0;
    if (x <= -reach) return 0.0;
    return psi(x + 0.5) - psi(x - 0.5);
  };
  const int rows = out.rect.height, cols = out.rect.width;
  const int count = static_cast<int>(strips.size());
  std::vector<double> row_weight(static_cast<size_t>(rows) * count);
  std::vector<double> chord(static_cast<size_t>(count) * cols);
  for (int r = 0; r < rows; ++r) {
    const double y = out.rect.y + r + 0.5;
    for (int k = 0; k < count; ++k) {
      const Strip& st = strips[k];
      row_weight[static_cast<size_t>(r) * count + k] = st.weight_px * st.radiance * h(st.y_px - y);
    }
  }
  for (int k = 0; k < count; ++k) {
    for (int col = 0; col < cols; ++col) {
      const double x = out.rect.x + col + 0.5;
      chord[static_cast<size_t>(k) * cols + col] =
          big_h(strips[k].right_px - x) - big_h(strips[k].left_px - x);
    }
  }
  for (int r = 0; r < rows; ++r) {
    float* dst = out.electrons[r];
    const double* wr = &row_weight[static_cast<size_t>(r) * count];
    for (int col = 0; col < cols; ++col) {
      double sum = 0.0;
      for (int k = 0; k < count; ++k) sum += wr[k] * chord[static_cast<size_t>(k) * cols + col];
      dst[col] = static_cast<float>(sum * scale);
    }
  }
  return out;
}

}  // namespace irdist::sim
