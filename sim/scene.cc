#include "sim/scene.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "base/pi.h"
#include "sim/disc_image.h"

namespace irdist::sim {
namespace {

constexpr double kDeg = kPi / 180.0;
constexpr double kPlanck = 6.62607015e-34;  // J s
constexpr double kLightSpeed = 2.99792458e8;  // m/s

using disc_image::Dot;
using disc_image::Vec3;

Vec3 AsVec3(const std::array<double, 3>& a) { return {a[0], a[1], a[2]}; }

// The chord's offset t (in radii, along the covered direction) that leaves `fraction` of the
// disc's area beyond it: (acos t - t sqrt(1 - t^2)) / pi = fraction, by bisection.
double SegmentOffset(double fraction) {
  double lo = -1.0, hi = 1.0;  // the covered area falls from 1 to 0 over [-1, 1]
  for (int i = 0; i < 100; ++i) {
    const double t = 0.5 * (lo + hi);
    const double covered = (std::acos(t) - t * std::sqrt(1.0 - t * t)) / kPi;
    (covered > fraction ? lo : hi) = t;
  }
  return 0.5 * (lo + hi);
}

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
  const OpticsOptions& o = physics_.optics;
  const double across = o.psf_sigma_minor_px > 0.0 ? o.psf_sigma_minor_px : o.psf_sigma_px;
  const double psf_var = 0.5 * (o.psf_sigma_px * o.psf_sigma_px + across * across);
  const double coc = CircleOfConfusionPx(distance_mm);
  return std::sqrt(psf_var + coc * coc / 16.0);
}

LensPsf Scene::PsfAt(double distance_mm) const {
  const OpticsOptions& o = physics_.optics;
  LensPsf psf;
  const double along = o.psf_sigma_px;
  const double across = o.psf_sigma_minor_px > 0.0 ? o.psf_sigma_minor_px : o.psf_sigma_px;
  const double a = o.psf_angle_deg * kDeg;
  const double c = std::cos(a), s = std::sin(a);
  psf.sxx_px2 = along * along * c * c + across * across * s * s;
  psf.syy_px2 = along * along * s * s + across * across * c * c;
  psf.sxy_px2 = (along * along - across * across) * c * s;
  const double coc = CircleOfConfusionPx(distance_mm);
  if (o.defocus_disc) {
    psf.disc_radius_px = 0.5 * coc;
  } else {  // the disc's per-axis variance c^2 / 16 as a Gaussian
    psf.sxx_px2 += coc * coc / 16.0;
    psf.syy_px2 += coc * coc / 16.0;
  }
  // A point (an ideal lens in focus) still spreads over the pixel: keep the core's sd >= 1e-3 px.
  psf.sxx_px2 = std::max(psf.sxx_px2, 1e-6);
  psf.syy_px2 = std::max(psf.syy_px2, 1e-6);
  psf.airy_first_zero_px = o.airy_first_zero_px;
  psf.halo_share = o.halo_share;
  psf.halo_sigma_px = o.halo_sigma_px;
  psf.pixel_aperture = physics_.sensor.pixel_aperture;
  return psf;
}

cv::Rect Scene::SignalRect(const EmitterImage& image, const LensPsf& psf) const {
  const SensorOptions& s = physics_.sensor;
  const double half =
      0.5 * image.major_px * 1.05 + std::max(psf.CoreReachPx(), psf.HaloReachPx()) + 2.0;
  const cv::Rect wanted(static_cast<int>(std::floor(image.center_x_px - half)),
                        static_cast<int>(std::floor(image.center_y_px - half)),
                        static_cast<int>(std::ceil(2 * half)) + 1,
                        static_cast<int>(std::ceil(2 * half)) + 1);
  return wanted & cv::Rect(0, 0, s.width_px, s.height_px);
}

namespace {

// What the strips of one disc share: its plane, conic, optional cut, and the camera.
struct StripGeometry {
  Vec3 n;
  double nc = 0.0;
  disc_image::DiscConic conic;
  const disc_image::ImageCut* cut = nullptr;  // null: the whole disc
  double f = 0.0, pitch_mm = 0.0, half_width_px = 0.0, half_height_px = 0.0;
  double area_m2 = 0.0, intensity_mw_sr = 0.0;
  bool lambertian = false, vignetting = false;
  int supersample = 8;
};

// The strip at height v (mm) of weight `weight_mm`, if its chord is visible and faces the camera.
void AppendStrip(const Scene& scene, const StripGeometry& g, double v, double weight_mm,
                 std::vector<ImageStrip>* strips) {
  double u_left = 0.0, u_right = 0.0;
  g.conic.Chord(v, &u_left, &u_right);
  if (g.cut != nullptr) {
    g.cut->Clip(v, &u_left, &u_right);
    if (u_right <= u_left) return;
  }
  const Vec3 ray = {0.5 * (u_left + u_right), v, g.f};
  const double n_ray = Dot(g.n, ray);
  if (std::fabs(n_ray) < 1e-12 || g.nc / n_ray <= 0.0) return;
  const Vec3 p = {g.nc / n_ray * ray.x, g.nc / n_ray * ray.y, g.nc / n_ray * ray.z};
  // Radiance of the disc towards the pinhole: I(a) / (A cos a), a = emission angle.
  const double cos_a = -Dot(g.n, p) / std::sqrt(Dot(p, p));
  if (cos_a <= 1e-6) return;
  const double pattern = g.lambertian ? cos_a : scene.Pattern(std::acos(std::min(1.0, cos_a)));
  double radiance = g.intensity_mw_sr * 1e-3 * pattern / (g.area_m2 * cos_a);
  if (g.vignetting) radiance *= std::pow(g.f / std::sqrt(Dot(ray, ray)), 4);
  strips->push_back({v / g.pitch_mm + g.half_height_px, weight_mm / g.pitch_mm,
                     u_left / g.pitch_mm + g.half_width_px, u_right / g.pitch_mm + g.half_width_px,
                     radiance});
}

// The strips of the rows |v - range.v_mid| <= range.v_half at Chebyshev-spaced heights v = mid +
// half sin(phi): phi evenly spaced (the midpoint rule) for a whole disc, whose chord vanishes as a
// square root at both ends; phi at Gauss-Legendre nodes for a cut disc's range, whose ends may be
// where the edge meets the conic (a chord that does not vanish there), and for a part of a range
// within one pixel row (`row_part`: at least 16 nodes, not 32).
void AppendStrips(const Scene& scene, const StripGeometry& g, const disc_image::StripRange& range,
                  bool row_part, std::vector<ImageStrip>* strips) {
  const double height_px = 2.0 * range.v_half / g.pitch_mm;
  const int nodes =
      std::max(row_part ? 16 : 32, static_cast<int>(std::ceil(g.supersample * height_px)));
  strips->reserve(strips->size() + nodes);
  if (g.cut == nullptr && !row_part) {
    for (int k = 0; k < nodes; ++k) {
      const double phi = -0.5 * kPi + (k + 0.5) * kPi / nodes;
      AppendStrip(scene, g, range.v_mid + range.v_half * std::sin(phi),
                  range.v_half * std::cos(phi) * kPi / nodes, strips);
    }
    return;
  }
  std::vector<double> x, w;
  disc_image::GaussLegendre(nodes, &x, &w);
  for (int k = 0; k < nodes; ++k) {
    const double phi = 0.5 * kPi * x[k];
    AppendStrip(scene, g, range.v_mid + range.v_half * std::sin(phi),
                range.v_half * std::cos(phi) * 0.5 * kPi * w[k], strips);
  }
}

// A range's strips (AppendStrips); behind a PSF sharper than kRowSplitSdPx along y, split where
// the pixels' sensitive heights begin and end (y_px = r + 0.5 -+ aperture / 2: the rows' borders
// for the whole pixel), each part Gauss-Legendre spaced.
void AppendRows(const Scene& scene, const StripGeometry& g, const disc_image::StripRange& range,
                const LensPsf& psf, std::vector<ImageStrip>* strips) {
  if (!(std::sqrt(psf.syy_px2) < kRowSplitSdPx)) {
    AppendStrips(scene, g, range, false, strips);
    return;
  }
  const auto v_of = [&](double y_px) { return (y_px - g.half_height_px) * g.pitch_mm; };
  const double lo = range.v_mid - range.v_half, hi = range.v_mid + range.v_half;
  const double y_lo = lo / g.pitch_mm + g.half_height_px, y_hi = hi / g.pitch_mm + g.half_height_px;
  std::vector<double> cuts;
  for (double r = std::floor(y_lo) - 1.0; r <= std::ceil(y_hi); r += 1.0) {
    const double half = 0.5 * psf.pixel_aperture;
    for (const double y : {r + 0.5 - half, r + 0.5 + half}) {
      if (y > y_lo && y < y_hi) cuts.push_back(v_of(y));
    }
  }
  std::sort(cuts.begin(), cuts.end());
  cuts.push_back(hi);
  double from = lo;
  for (const double to : cuts) {
    if (to > from) AppendStrips(scene, g, {0.5 * (from + to), 0.5 * (to - from)}, true, strips);
    from = std::max(from, to);
  }
}

// The strips through the lens: (1 - halo share) of the light through the core (and the defocus
// disc), the halo's share through its wide round Gaussian.
void IntegrateThroughPsf(const std::vector<ImageStrip>& strips, const LensPsf& psf, double scale,
                         const cv::Rect& rect, cv::Mat1f* out) {
  if (strips.empty()) return;
  disc_image::IntegrateStripsCore(strips, psf, scale * (1.0 - psf.halo_share), rect, out);
  if (!(psf.halo_share > 0.0)) return;
  const disc_image::PixelResponse halo(psf.halo_sigma_px, psf.pixel_aperture);
  disc_image::IntegrateStrips(strips, halo, halo, scale * psf.halo_share, rect, out);
}

}  // namespace

std::vector<ImageStrip> Scene::DiscStrips(const DiscSource& disc, const LensPsf& psf) const {
  const OpticsOptions& o = physics_.optics;
  const SensorOptions& s = physics_.sensor;
  StripGeometry g;
  g.f = o.focal_length_mm;
  g.pitch_mm = s.pixel_pitch_um * 1e-3;
  g.half_width_px = 0.5 * s.width_px;
  g.half_height_px = 0.5 * s.height_px;
  g.n = AsVec3(disc.axis);
  const Vec3 c = AsVec3(disc.center_mm);
  g.nc = Dot(g.n, c);
  const double radius2 = 0.25 * disc.diameter_mm * disc.diameter_mm;
  g.area_m2 = kPi * radius2 * 1e-6;
  g.intensity_mw_sr = disc.intensity_mw_sr;
  g.lambertian = disc.lambertian;
  g.vignetting = o.vignetting;
  g.supersample = o.supersample;
  g.conic = disc_image::MakeDiscConic(g.n, c, radius2, g.f);
  std::vector<ImageStrip> strips;
  if (!g.conic.in_view) return strips;
  if (!disc.cut) {
    AppendRows(*this, g, {g.conic.v_mid, g.conic.v_half}, psf, &strips);
    return strips;
  }
  const disc_image::ImageCut cut = disc_image::MakeImageCut(
      g.n, c, AsVec3(disc.cut_direction), disc.cut_offset_mm, g.f);
  g.cut = &cut;
  for (const disc_image::StripRange& range : disc_image::VisibleRanges(g.conic, cut)) {
    AppendRows(*this, g, range, psf, &strips);
  }
  return strips;
}

DiscSource Scene::EmitterDisc(const PoseState& pose, double intensity_mw_sr) const {
  const EmitterOptions& e = physics_.emitter;
  DiscSource disc;
  disc.center_mm = {e.offset_x_mm, e.offset_y_mm, pose.slide_mm};
  const Vec3 n = EmissionAxis(pose);
  disc.axis = {n.x, n.y, n.z};
  disc.diameter_mm = e.diameter_mm;
  disc.intensity_mw_sr = intensity_mw_sr;
  const OccluderOptions& occluder = physics_.scene.occluder;
  if (occluder.On()) {
    // The disc's own axes: the pan-tilt mount (pan about y, then tilt about x) carries the
    // image's x and y, as it carries (0, 0, -1) to the emission axis.
    const double p = pose.pan_deg * kDeg, t = pose.tilt_deg * kDeg;
    const Vec3 x_axis = {std::cos(p), 0.0, std::sin(p)};
    const Vec3 y_axis = {-std::sin(t) * std::sin(p), std::cos(t), std::sin(t) * std::cos(p)};
    const double a = occluder.edge_angle_deg * kDeg;
    disc.cut = true;
    disc.cut_direction = {std::cos(a) * x_axis.x + std::sin(a) * y_axis.x,
                          std::cos(a) * x_axis.y + std::sin(a) * y_axis.y,
                          std::cos(a) * x_axis.z + std::sin(a) * y_axis.z};
    disc.cut_offset_mm = 0.5 * e.diameter_mm * SegmentOffset(occluder.covered_fraction);
  }
  return disc;
}

SignalWindow Scene::RenderDisc(const DiscSource& disc, double exposure_s) const {
  const SensorOptions& s = physics_.sensor;
  const double f = physics_.optics.focal_length_mm;
  const double pitch_mm = s.pixel_pitch_um * 1e-3;
  const Vec3 c = AsVec3(disc.center_mm);
  const double z = std::max(c.z, 1.0);
  EmitterImage image;
  image.center_x_px = 0.5 * s.width_px + f * c.x / z / pitch_mm;
  image.center_y_px = 0.5 * s.height_px + f * c.y / z / pitch_mm;
  image.major_px = disc.diameter_mm * f / std::sqrt(Dot(c, c)) / pitch_mm;
  const LensPsf psf = PsfAt(c.z);
  SignalWindow out;
  out.rect = SignalRect(image, psf);
  if (out.rect.empty()) return out;
  out.electrons = cv::Mat1f::zeros(out.rect.height, out.rect.width);
  if (disc.intensity_mw_sr <= 0.0 || exposure_s <= 0.0 || c.z <= 0.0) return out;
  IntegrateThroughPsf(DiscStrips(disc, psf), psf, electrons_per_radiance_s_ * exposure_s,
                      out.rect, &out.electrons);
  return out;
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
  const LensPsf psf = PsfAt(pose.slide_mm);
  SignalWindow out;
  out.rect = SignalRect(image, psf);
  if (out.rect.empty()) return out;
  out.electrons = cv::Mat1f::zeros(out.rect.height, out.rect.width);
  if (intensity_mw_sr <= 0.0 || exposure_s <= 0.0) return out;
  IntegrateThroughPsf(DiscStrips(EmitterDisc(pose, intensity_mw_sr), psf), psf,
                      electrons_per_radiance_s_ * exposure_s, out.rect, &out.electrons);
  return out;
}

}  // namespace irdist::sim
