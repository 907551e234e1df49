#include "sim/scene.h"

#include <algorithm>
#include <cmath>

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

  const double f = o.focal_length_mm;
  const double pitch_mm = s.pixel_pitch_um * 1e-3;
  const double cx = 0.5 * s.width_px;
  const double cy = 0.5 * s.height_px;
  const Vec3 n = EmissionAxis(pose);
  const Vec3 c = {e.offset_x_mm, e.offset_y_mm, pose.slide_mm};
  const double n_dot_c = Dot(n, c);
  const double radius2 = 0.25 * e.diameter_mm * e.diameter_mm;
  const double area_m2 = kPi * radius2 * 1e-6;
  const double intensity_w_sr = intensity_mw_sr * 1e-3;
  const int ss = o.supersample;
  const double inv_ss = 1.0 / ss;
  const double scale = electrons_per_radiance_s_ * exposure_s / (ss * ss);

  // Radiance towards the pinhole (times cos^4 vignetting) of the disc point hit by the ray
  // through image point (x_mm, y_mm); 0 when the ray misses the disc. `hit_r2` gets the squared
  // distance of the hit from the disc centre and `ray_t` the ray parameter.
  auto sample = [&](double x_mm, double y_mm, double* hit_r2, double* ray_t) {
    const Vec3 ray = {x_mm, y_mm, f};
    const double denom = Dot(n, ray);
    *hit_r2 = 1e300;
    *ray_t = 0.0;
    if (std::fabs(denom) < 1e-12) return 0.0;
    const double t = n_dot_c / denom;
    if (t <= 0.0) return 0.0;
    *ray_t = t;
    const Vec3 p = {t * ray.x, t * ray.y, t * ray.z};
    const Vec3 dp = {p.x - c.x, p.y - c.y, p.z - c.z};
    *hit_r2 = Dot(dp, dp);
    if (*hit_r2 > radius2) return 0.0;
    // Radiance of the disc towards the pinhole: I(a) / (A cos a), a = emission angle.
    const double cos_a = -Dot(n, p) / std::sqrt(Dot(p, p));
    if (cos_a <= 1e-6) return 0.0;
    const double radiance =
        intensity_w_sr * Pattern(std::acos(std::min(1.0, cos_a))) / (area_m2 * cos_a);
    double falloff = 1.0;
    if (o.vignetting) {
      const double cos_field = f / std::sqrt(Dot(ray, ray));
      falloff = cos_field * cos_field * cos_field * cos_field;
    }
    return radiance * falloff;
  };
  const double radius = std::sqrt(radius2);
  const double cos_theta = std::max(0.05, std::cos(image.theta_deg * kDeg));
  for (int row = 0; row < out.rect.height; ++row) {
    float* dst = out.electrons[row];
    for (int col = 0; col < out.rect.width; ++col) {
      // The pixel's centre decides whether it lies wholly inside or outside the disc's image
      // (one sample suffices: the radiance varies negligibly across a pixel) or straddles its
      // edge (then it is integrated with ss x ss sub-samples).
      double r2 = 0.0, t = 0.0;
      const double centre = sample((out.rect.x + col + 0.5 - cx) * pitch_mm,
                                   (out.rect.y + row + 0.5 - cy) * pitch_mm, &r2, &t);
      // Half-diagonal of the pixel on the disc plane (t * pitch), with margin and foreshortening.
      const double footprint_mm = 1.5 * pitch_mm * t / cos_theta;
      const double r = std::sqrt(r2);
      if (t > 0.0 && r + footprint_mm < radius) {
        dst[col] = static_cast<float>(centre * scale * ss * ss);
        continue;
      }
      if (t > 0.0 && r - footprint_mm > radius) continue;
      double sum = 0.0;
      for (int sy = 0; sy < ss; ++sy) {
        const double y_mm = (out.rect.y + row + (sy + 0.5) * inv_ss - cy) * pitch_mm;
        for (int sx = 0; sx < ss; ++sx) {
          const double x_mm = (out.rect.x + col + (sx + 0.5) * inv_ss - cx) * pitch_mm;
          sum += sample(x_mm, y_mm, &r2, &t);
        }
      }
      dst[col] = static_cast<float>(sum * scale);
    }
  }
  if (psf > 0.0) {
    cv::GaussianBlur(out.electrons, out.electrons, cv::Size(0, 0), psf, psf,
                     cv::BORDER_CONSTANT);
  }
  return out;
}

}  // namespace irdist::sim
