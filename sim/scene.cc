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

double Scene::CircleOfConfusionPx(double distance_mm) const {
  const OpticsOptions& o = physics_.optics;
  if (o.focus_mm <= 0.0) return 0.0;
  const double f = o.focal_length_mm;
  const double d = std::max(distance_mm, 2.0 * f);
  const double aperture_mm = f / o.f_number;
  const double coc_mm = aperture_mm * f * std::fabs(d - o.focus_mm) / (d * (o.focus_mm - f));
  return coc_mm / (physics_.sensor.pixel_pitch_um * 1e-3);
}

double Scene::BlurSigmaPx(double distance_mm) const {
  const double psf = physics_.optics.psf_sigma_px;
  const double coc = CircleOfConfusionPx(distance_mm);
  return std::sqrt(psf * psf + coc * coc / 16.0);
}

cv::Rect Scene::SignalRect(const EmitterImage& image, double blur_px) const {
  const SensorOptions& s = physics_.sensor;
  const double half = 0.5 * image.major_px * 1.05 + 4.0 * blur_px + 2.0;
  const cv::Rect wanted(static_cast<int>(std::floor(image.center_x_px - half)),
                        static_cast<int>(std::floor(image.center_y_px - half)),
                        static_cast<int>(std::ceil(2 * half)) + 1,
                        static_cast<int>(std::ceil(2 * half)) + 1);
  return wanted & cv::Rect(0, 0, s.width_px, s.height_px);
}

// One horizontal strip of the disc's image: its y (px), weight (px), chord ends (px), radiance.
struct ImageStrip {
  double y_px, weight_px, left_px, right_px, radiance;
};

namespace {

// The disc's image in the image plane (mm): the ray (u, v, f) meets the disc's plane at
// t (u, v, f), t = nc / n.ray; it lands inside the disc iff |nc ray - (n.ray) c|^2 <= R^2 (n.ray)^2.
// With ray = (0, v, f) + u e_x this is A u^2 + 2 B(v) u + C(v) <= 0, B linear and C quadratic in v.
struct DiscConic {
  double qa = 0.0, b0 = 0.0, b1 = 0.0, c0 = 0.0, c1 = 0.0, c2 = 0.0;
  double v_mid = 0.0, v_half = 0.0;  // the chord exists for |v - v_mid| <= v_half
  bool in_view = false;
  // Chord ends (mm) at height v.
  void Chord(double v, double* u_left, double* u_right) const {
    const double b = b0 + b1 * v;
    const double d = std::max(0.0, b * b - qa * (c0 + 2.0 * c1 * v + c2 * v * v));
    *u_left = (-b - std::sqrt(d)) / qa;
    *u_right = (-b + std::sqrt(d)) / qa;
  }
};

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

// The pixel's response to a Gaussian blur of `sigma` px: h(x) = PSF convolved with the unit box,
// and H(x) its integral from -infinity (closed forms with Phi and phi).
class PixelResponse {
 public:
  explicit PixelResponse(double sigma) : sigma_(sigma), reach_(0.5 + 8.0 * std::max(sigma, 1e-9)) {}
  double h(double x) const { return std::fabs(x) >= reach_ ? 0.0 : Step(x + 0.5) - Step(x - 0.5); }
  double H(double x) const {
    if (x >= reach_) return 1.0;
    if (x <= -reach_) return 0.0;
    return Psi(x + 0.5) - Psi(x - 0.5);
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
  double sigma_, reach_;
};

// Sums, per pixel of `out`, the strips weighted by h(row) and H across each chord, times `scale`.
void IntegrateStrips(const std::vector<ImageStrip>& strips, const PixelResponse& response,
                     double scale, const cv::Rect& rect, cv::Mat1f* out) {
  const int rows = rect.height, cols = rect.width;
  const int count = static_cast<int>(strips.size());
  std::vector<double> row_weight(static_cast<size_t>(rows) * count);
  std::vector<double> chord(static_cast<size_t>(count) * cols);
  for (int r = 0; r < rows; ++r) {
    const double y = rect.y + r + 0.5;
    for (int k = 0; k < count; ++k) {
      const ImageStrip& st = strips[k];
      row_weight[static_cast<size_t>(r) * count + k] =
          st.weight_px * st.radiance * response.h(st.y_px - y);
    }
  }
  for (int k = 0; k < count; ++k) {
    for (int col = 0; col < cols; ++col) {
      const double x = rect.x + col + 0.5;
      chord[static_cast<size_t>(k) * cols + col] =
          response.H(strips[k].right_px - x) - response.H(strips[k].left_px - x);
    }
  }
  for (int r = 0; r < rows; ++r) {
    float* dst = (*out)[r];
    const double* wr = &row_weight[static_cast<size_t>(r) * count];
    for (int col = 0; col < cols; ++col) {
      double sum = 0.0;
      for (int k = 0; k < count; ++k) sum += wr[k] * chord[static_cast<size_t>(k) * cols + col];
      dst[col] = static_cast<float>(sum * scale);
    }
  }
}

}  // namespace

std::vector<ImageStrip> Scene::DiscStrips(const PoseState& pose, double intensity_mw_sr) const {
  const EmitterOptions& e = physics_.emitter;
  const OpticsOptions& o = physics_.optics;
  const SensorOptions& s = physics_.sensor;
  const double f = o.focal_length_mm;
  const double pitch_mm = s.pixel_pitch_um * 1e-3;
  const Vec3 n = EmissionAxis(pose);
  const Vec3 c = {e.offset_x_mm, e.offset_y_mm, pose.slide_mm};
  const double nc = Dot(n, c);
  const double radius2 = 0.25 * e.diameter_mm * e.diameter_mm;
  const double area_m2 = kPi * radius2 * 1e-6;
  const DiscConic conic = MakeDiscConic(n, c, radius2, f);
  std::vector<ImageStrip> strips;
  if (!conic.in_view) return strips;
  const double height_px = 2.0 * conic.v_half / pitch_mm;
  const int nodes = std::max(32, static_cast<int>(std::ceil(o.supersample * height_px)));
  strips.reserve(nodes);
  for (int k = 0; k < nodes; ++k) {
    const double phi = -0.5 * kPi + (k + 0.5) * kPi / nodes;
    const double v = conic.v_mid + conic.v_half * std::sin(phi);
    double u_left = 0.0, u_right = 0.0;
    conic.Chord(v, &u_left, &u_right);
    const Vec3 ray = {0.5 * (u_left + u_right), v, f};
    const double n_ray = Dot(n, ray);
    if (std::fabs(n_ray) < 1e-12 || nc / n_ray <= 0.0) continue;
    const Vec3 p = {nc / n_ray * ray.x, nc / n_ray * ray.y, nc / n_ray * ray.z};
    // Radiance of the disc towards the pinhole: I(a) / (A cos a), a = emission angle.
    const double cos_a = -Dot(n, p) / std::sqrt(Dot(p, p));
    if (cos_a <= 1e-6) continue;
    double radiance =
        intensity_mw_sr * 1e-3 * Pattern(std::acos(std::min(1.0, cos_a))) / (area_m2 * cos_a);
    if (o.vignetting) radiance *= std::pow(f / std::sqrt(Dot(ray, ray)), 4);
    strips.push_back({v / pitch_mm + 0.5 * s.height_px,
                      conic.v_half * std::cos(phi) * kPi / nodes / pitch_mm,
                      u_left / pitch_mm + 0.5 * s.width_px, u_right / pitch_mm + 0.5 * s.width_px,
                      radiance});
  }
  return strips;
}

SignalWindow Scene::RenderSignal(const PoseState& pose, double intensity_mw_sr,
                                 double exposure_s) const {
  // The pixel value is the disc's image (radiance x camera equation) convolved with the Gaussian
  // blur (lens PSF and defocus at this distance) and integrated over the pixel's square, exactly:
  // the pixel's response to a point is separable, h(x) h(y) with h = blur convolved with the
  // pixel's width, so a pixel sums, over thin horizontal strips of the disc's image, h(strip y -
  // pixel y) times the integral of h across the strip's chord (closed form). The strips are
  // Chebyshev-spaced in y (nodes at y = centre + half-height * sin(phi), phi evenly spaced), which
  // makes the chord's square-root ends smooth, so the sum converges fast. Radiance is taken at
  // each chord's midpoint (it varies by < 0.5 % across the disc, linearly to first order). No
  // sampling of the sharp disc happens anywhere, so nothing aliases: sampling a sharp edge on a
  // grid and blurring afterwards put a pose-dependent error of up to +-0.5 deg into the shape.
  const EmitterImage image = Project(pose);
  const double blur_px = BlurSigmaPx(pose.slide_mm);
  SignalWindow out;
  out.rect = SignalRect(image, blur_px);
  if (out.rect.empty()) return out;
  out.electrons = cv::Mat1f::zeros(out.rect.height, out.rect.width);
  if (intensity_mw_sr <= 0.0 || exposure_s <= 0.0) return out;
  const std::vector<ImageStrip> strips = DiscStrips(pose, intensity_mw_sr);
  if (strips.empty()) return out;
  IntegrateStrips(strips, PixelResponse(blur_px), electrons_per_radiance_s_ * exposure_s, out.rect,
                  &out.electrons);
  return out;
}

}  // namespace irdist::sim
