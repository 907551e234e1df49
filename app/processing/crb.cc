#include "app/processing/crb.h"

#include <algorithm>
#include <cmath>
#include <mutex>
#include <boost/math/tools/roots.hpp>
#include <opencv2/core.hpp>
#include <sstream>

#include "acquisition/recording_reader.h"
#include "app/inputs/rig.h"
#include "base/check.h"
#include "base/pi.h"
#include "sim/scene.h"
#include "sim/sensor.h"

namespace irdist {
namespace {

constexpr int kCanvasMarginPx = 6;  // beyond the unperturbed blob's window: room for the steps

// d_mm moves the emitter along its line of sight from where it is at d0_mm (the rig's lateral
// offset scales with it): the image stays in place and only x_px, y_px move it. Moving the slide
// instead would also shift an off-axis blob (f X / d), and a shift of a px across the central
// difference's 2 x 20 mm is not the translation the x/y columns take out: that remainder read as
// information on d and made the bound 4x too small 50 mm off the axis at 1.5 m.
struct Point {
  double theta_deg, x_px, y_px, d_mm, d0_mm;
};

// Central-difference steps: large enough that the disc's edge moves well across the strips,
// small enough to stay linear.
constexpr double kStepThetaDeg = 0.5, kStepPx = 0.25, kStepMm = 20.0;

// Expected signal electrons for one second of exposure at unit on-axis intensity (1 mW/sr),
// on `canvas` (full-sensor pixels). The blob is moved by x/y pixels through the emitter's offset.
cv::Mat1d Render(const sim::RigPhysics& base, const Point& p, const cv::Rect& canvas,
                 cv::Rect* window = nullptr) {
  sim::RigPhysics physics = base;
  const double mm_per_px =
      physics.sensor.pixel_pitch_um * 1e-3 * p.d_mm / physics.optics.focal_length_mm;
  const double along_ray = p.d_mm / p.d0_mm;
  physics.emitter.offset_x_mm = base.emitter.offset_x_mm * along_ray + p.x_px * mm_per_px;
  physics.emitter.offset_y_mm = base.emitter.offset_y_mm * along_ray + p.y_px * mm_per_px;
  const sim::Scene scene(physics);
  sim::PoseState pose;
  pose.slide_mm = p.d_mm;
  pose.pan_deg = p.theta_deg;
  pose.bias_ma = 1.0;  // on: the intensity is given
  // The charge as collected: crosstalk included.
  const sim::SignalWindow w =
      sim::DiffuseCharge(scene.RenderSignal(pose, 1.0, 1.0), physics.sensor);
  if (window) *window = w.rect;
  cv::Mat1d out = cv::Mat1d::zeros(std::max(canvas.height, 0), std::max(canvas.width, 0));
  const cv::Rect inside = w.rect & canvas;
  if (inside.empty()) return out;
  cv::Mat1d part;
  w.electrons(inside - w.rect.tl()).convertTo(part, CV_64F);
  part.copyTo(out(inside - canvas.tl()));
  return out;
}

// d mu / d param at `at` by central differences (one-sided at theta < step: the image is even in
// theta, so the centred difference would vanish).
cv::Mat1d Derivative(const sim::RigPhysics& physics, const Point& at, const cv::Rect& canvas,
                     int param) {
  double Point::*field = param == kCrbTheta ? &Point::theta_deg
                         : param == kCrbX   ? &Point::x_px
                         : param == kCrbY   ? &Point::y_px
                                            : &Point::d_mm;
  const double step = param == kCrbTheta ? kStepThetaDeg : param == kCrbD ? kStepMm : kStepPx;
  Point plus = at, minus = at;
  plus.*field += step;
  double span = 2.0 * step;
  if (param == kCrbTheta && at.theta_deg < step) {
    span = step;
  } else {
    minus.*field -= step;
  }
  cv::Mat1d g = (Render(physics, plus, canvas) - Render(physics, minus, canvas)) / span;
  if (param == kCrbTheta) g *= 180.0 / kPi;  // per radian
  return g;
}

// The expected image and its derivatives for one second at unit intensity; ln I0's derivative is
// the image itself.
FrameSensitivity UnitSensitivity(const sim::RigPhysics& physics, const CrbConditions& c) {
  const Point at{c.theta_deg, 0.0, 0.0, c.d_mm, c.d_mm};
  cv::Rect window;
  Render(physics, at, cv::Rect(), &window);
  const cv::Rect sensor(0, 0, physics.sensor.width_px, physics.sensor.height_px);
  const cv::Rect canvas = (window - cv::Point(kCanvasMarginPx, kCanvasMarginPx) +
                           cv::Size(2 * kCanvasMarginPx, 2 * kCanvasMarginPx)) &
                          sensor;
  FrameSensitivity unit;
  unit.expected_e = Render(physics, at, canvas);
  unit.derivatives[kCrbLnI0] = unit.expected_e.clone();
  for (int k = kCrbTheta; k < kNumCrbParams; ++k) {
    unit.derivatives[k] = Derivative(physics, at, canvas, k);
  }
  return unit;
}

// The unit sensitivity scaled to one frame of `exposure_ms` at `intensity_mw_sr`, with its noise.
FrameSensitivity ScaledFrame(const FrameSensitivity& unit, const sim::SensorOptions& s,
                             double intensity_mw_sr, double exposure_ms) {
  const double scale = intensity_mw_sr * exposure_ms * 1e-3;
  FrameSensitivity f;
  f.expected_e = unit.expected_e * scale;
  for (int k = 0; k < kNumCrbParams; ++k) f.derivatives[k] = unit.derivatives[k] * scale;
  f.noise.read_noise_e = s.read_noise_e;
  f.noise.dark_e = (s.dark_current_e_per_s + s.background_e_per_s) * exposure_ms * 1e-3;
  f.noise.system_gain_dn_per_e = s.system_gain_dn_per_e;
  return f;
}

double SampleSd(const std::vector<double>& v) {
  if (v.size() < 2) return 0.0;
  double mean = 0.0;
  for (double x : v) mean += x;
  mean /= static_cast<double>(v.size());
  double ss = 0.0;
  for (double x : v) ss += (x - mean) * (x - mean);
  return std::sqrt(ss / static_cast<double>(v.size() - 1));
}

}  // namespace

double SteadyJunctionRiseK(const sim::RigPhysics& physics, double bias_ma) {
  return physics.emitter.thermal_resistance_k_per_w * bias_ma * 1e-3 *
         physics.emitter.forward_voltage_v;
}

CrbResult ComputeCrb(const sim::RigPhysics& physics, const CrbConditions& c) {
  IRDIST_CHECK(c.d_mm > 0.0 && !c.exposures_ms.empty(), "ComputeCrb: d ", c.d_mm, " mm with ",
               c.exposures_ms.size(), " exposures");
  sim::RigPhysics fine = physics;  // enough strips that the finite differences are smooth
  fine.optics.supersample = std::max(fine.optics.supersample, 32);
  const FrameSensitivity unit = UnitSensitivity(fine, c);
  const sim::Scene scene(physics);
  const double intensity = scene.OnAxisIntensityMwSr(c.bias_ma, c.junction_rise_k);
  std::vector<FrameSensitivity> frames;
  for (double t_ms : c.exposures_ms) {
    frames.push_back(ScaledFrame(unit, physics.sensor, intensity, t_ms));
  }
  return ComputeFrameCrb(frames, c.theta_deg > 0.0);
}

namespace {

// Exposures of the recording's first complete bracket: reference, then measurements (ms).
std::vector<double> BracketExposuresMs(const RecordingReader& reader) {
  for (const RecordedBracket& b : reader.Brackets()) {
    if (!b.complete || b.Reference() == nullptr) continue;
    std::vector<double> out = {b.Reference()->requested_exposure_us * 1e-3};
    for (const FrameRecord* m : b.Measurements()) out.push_back(m->requested_exposure_us * 1e-3);
    if (out.size() >= 2) return out;
  }
  return {};
}

std::string KeyOf(const RecordingCrbSource& source, const CrbConditions& c) {
  std::ostringstream key;
  key.precision(10);
  key << source.identity << '|' << c.d_mm << '|' << c.theta_deg << '|' << c.bias_ma << '|'
      << c.junction_rise_k;
  return key.str();
}

// ComputeCrb once per process for each rig, exposures and condition.
CrbResult CachedCrb(const RecordingCrbSource& source, const CrbConditions& c) {
  static std::mutex mutex;
  static std::map<std::string, CrbResult> cache;
  const std::string key = KeyOf(source, c);
  {
    const std::lock_guard<std::mutex> lock(mutex);
    const auto it = cache.find(key);
    if (it != cache.end()) return it->second;
  }
  const CrbResult result = ComputeCrb(source.physics, c);
  const std::lock_guard<std::mutex> lock(mutex);
  cache[key] = result;
  return result;
}

constexpr const char* kCrbSource =
    "virtual rig physics (the recording's rig.yaml) and the sensor's EMVA 1288 temporal noise; "
    "unknowns ln I0, theta, blob x/y, d shared by the bracket's frames; junction at its "
    "steady-state rise";

}  // namespace

RecordingCrbSource CrbSourceOfRecording(const std::string& recording_dir) {
  RecordingCrbSource source;
  try {
    const RecordingReader reader(recording_dir);
    const RecordingHeader& h = reader.header();
    if (h.rig_text.empty()) {
      source.why = "the recording does not hold its rig file";
      return source;
    }
    if (ParseRig(h.rig_text, recording_dir + "/rig.yaml").kind != RigKind::kVirtual) {
      source.why = "hardware rig: the bound needs the scene's physics, known on a virtual rig only";
      return source;
    }
    source.physics = sim::LoadRigPhysics(recording_dir + "/rig.yaml");
    source.exposures_ms = BracketExposuresMs(reader);
    if (source.exposures_ms.empty()) {
      source.why = "the recording has no complete bracket";
      return source;
    }
    std::ostringstream identity;
    identity.precision(10);
    identity << h.rig_text;
    for (double t : source.exposures_ms) identity << '|' << t;
    source.identity = identity.str();
    source.available = true;
  } catch (const std::exception& e) {  // the bound is an addition: it never fails a validation
    source.why = std::string("the recording's rig could not be read: ") + e.what();
  }
  return source;
}

namespace {

// The figures of the repeated conditions: each one's dispersion against its bound.
void AddDispersion(const ConditionErrors& c, const CrbResult& bound, CrbFigures* out) {
  if (c.d_error_mm.size() < 2) return;
  CrbPoseRatio p;
  p.d_mm = c.d_mm;
  p.theta_deg = c.theta_deg;
  p.bias_ma = c.bias_ma;
  p.repeats = static_cast<int>(c.d_error_mm.size());
  p.distance_sd_mm = SampleSd(c.d_error_mm);
  p.distance_sd_bound_mm = bound.d_sd_mm;
  p.theta_sd_deg = SampleSd(c.theta_error_deg);
  p.theta_sd_bound_deg = bound.theta_sd_deg;
  out->dispersion.push_back(p);
  const double ratio = p.distance_sd_mm / p.distance_sd_bound_mm;
  out->dispersion_ratio_max = std::max(out->dispersion_ratio_max.value_or(0.0), ratio);
  if (p.theta_sd_bound_deg > 0.0) {
    const double theta_ratio = p.theta_sd_deg / p.theta_sd_bound_deg;
    out->theta_dispersion_ratio_max =
        std::max(out->theta_dispersion_ratio_max.value_or(0.0), theta_ratio);
  }
}

// Sums over the rows for the rms figures.
struct RmsSums {
  double d_z2 = 0.0;
  int d_rows = 0;
  double theta_err2 = 0.0, theta_bound2 = 0.0, theta_z2 = 0.0;
  int theta_rows = 0;
  std::vector<double> theta_bounds_deg;  // one per row
};

// The p-quantile of max_i |e_i| for independent e_i ~ N(0, sd_i^2): the x where
// prod_i erf(x / (sd_i sqrt 2)) = p.
double MaxAbsQuantile(const std::vector<double>& sd, double p) {
  if (sd.empty()) return NAN;
  const auto cdf_minus_p = [&sd, p](double x) {
    double log_cdf = 0.0;
    for (double s : sd) log_cdf += std::log(std::max(std::erf(x / (s * std::sqrt(2.0))), 1e-300));
    return std::exp(log_cdf) - p;
  };
  const double hi = 20.0 * *std::max_element(sd.begin(), sd.end());
  const auto bracket = boost::math::tools::bisect(
      cdf_minus_p, 0.0, hi, boost::math::tools::eps_tolerance<double>(40));
  return 0.5 * (bracket.first + bracket.second);
}

void AddRows(const ConditionErrors& c, const CrbResult& bound, RmsSums* sums) {
  for (double e : c.d_error_mm) {
    sums->d_z2 += (e / bound.d_sd_mm) * (e / bound.d_sd_mm);
    ++sums->d_rows;
  }
  if (c.theta_deg < 15.0 || !(bound.theta_sd_deg > 0.0)) return;
  for (double e : c.theta_error_deg) {
    sums->theta_err2 += e * e;
    sums->theta_bound2 += bound.theta_sd_deg * bound.theta_sd_deg;
    sums->theta_z2 += (e / bound.theta_sd_deg) * (e / bound.theta_sd_deg);
    ++sums->theta_rows;
    sums->theta_bounds_deg.push_back(bound.theta_sd_deg);
  }
}

void Widen(double value, bool first, double* lo, double* hi) {
  *lo = first ? value : std::min(*lo, value);
  *hi = first ? value : std::max(*hi, value);
}

}  // namespace

CrbFigures MethodCrb(const RecordingCrbSource& source, const MethodSummary& method) {
  CrbFigures out;
  if (!source.available) {
    out.source = "not computed: " + source.why;
    return out;
  }
  out.available = true;
  out.source = kCrbSource;
  RmsSums sums;
  for (const ConditionErrors& c : method.conditions) {
    const CrbConditions conditions{c.d_mm, c.theta_deg, c.bias_ma,
                                   SteadyJunctionRiseK(source.physics, c.bias_ma),
                                   source.exposures_ms};
    const CrbResult bound = CachedCrb(source, conditions);
    if (!bound.valid) continue;
    Widen(bound.d_sd_mm, out.conditions == 0, &out.distance_sd_bound_mm_min,
          &out.distance_sd_bound_mm_max);
    ++out.conditions;
    if (c.theta_deg >= 15.0 && bound.theta_sd_deg > 0.0) {
      Widen(bound.theta_sd_deg, out.theta_ge15_count == 0, &out.theta_ge15_sd_bound_deg_min,
            &out.theta_ge15_sd_bound_deg_max);
      out.theta_ge15_count += static_cast<int>(c.theta_error_deg.size());
    }
    AddRows(c, bound, &sums);
    AddDispersion(c, bound, &out);
  }
  if (sums.d_rows > 0) out.distance_error_over_bound_rms = std::sqrt(sums.d_z2 / sums.d_rows);
  if (sums.theta_rows > 0) {
    out.theta_ge15_error_rms_deg = std::sqrt(sums.theta_err2 / sums.theta_rows);
    out.theta_ge15_sd_bound_rms_deg = std::sqrt(sums.theta_bound2 / sums.theta_rows);
    out.theta_ge15_error_over_bound_rms = std::sqrt(sums.theta_z2 / sums.theta_rows);
    out.theta_ge15_max_at_bound_deg_median = MaxAbsQuantile(sums.theta_bounds_deg, 0.5);
    out.theta_ge15_max_at_bound_deg_p95 = MaxAbsQuantile(sums.theta_bounds_deg, 0.95);
  }
  return out;
}

std::map<std::string, CrbFigures> ValidationCrb(const std::map<std::string, std::string>& context,
                                                const ValidationSummary& summary) {
  std::map<std::string, CrbFigures> out;
  const auto recording = context.find("recording");
  if (recording == context.end() || summary.methods.empty()) return out;
  const RecordingCrbSource source = CrbSourceOfRecording(recording->second);
  for (const MethodSummary& m : summary.methods) out[m.method] = MethodCrb(source, m);
  return out;
}

}  // namespace irdist
