// Accuracy study on the virtual rig without GigE or serial: frames rendered directly with
// sim::Renderer (sensor noise, per-frame seeds, the IRED's self-heating along the sweep), the
// Table 3 calibration fitted, and the validation grids of Fig. 10, 13 and 14 estimated by every
// method: the paper's pipeline (Algorithm 1 per t_n, full Eq. 17-18, fixed window), the default
// pipeline (estimator defaults), the I0-dependent direct model at the nominal current and the
// geometric baseline; pipeline `response` is the default estimator on features linearised by the
// camera response recovered from the calibration's brackets (estimator/response.h). Prints the
// issue-6 figures. Usage:
//   irdist_accuracy_study [--rig recipes/rigs/virtual.yaml] [--seed N] [--quick] [--crb-only]
//                         [--nonlinearity A]
// Rigs with a blur after the pixels: --rig recipes/rigs/virtual-crosstalk.yaml (0.6 px
// of inter-pixel crosstalk) and virtual-sharp.yaml (0.3 px optics, 0.8 px crosstalk); the bound
// below includes the crosstalk (app/processing/crb.cc diffuses the charge as the sensor does).
// It also prints the Cramer-Rao bound on d and theta at 2.7 m (app/processing/crb.h, the code behind
// summary.yaml's `crb:`) for the Fig. 14 conditions, for one (t_r, t_n) pair and for a whole
// bracket, beside the measured dispersion of Fig. 14.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "app/processing/crb.h"
#include "estimator/blob_fit.h"
#include "estimator/estimate.h"
#include "estimator/estimate_baselines.h"
#include "estimator/features.h"
#include "estimator/fit.h"
#include "estimator/health.h"
#include "estimator/response.h"
#include "sim/renderer.h"
#include "sim/rig_physics.h"

namespace irdist {
namespace {

constexpr double kTRefMs = 8.0;

struct Pose {
  double d_mm, theta_deg, bias_ma;
  int rep;
};

struct Bracket {
  Pose pose;
  Features reference;
  std::vector<Features> measurements;
  std::vector<double> t_ms;
  double rise_k = 0.0;  // junction rise at the reference frame
};

// Renders sweeps with the IRED's thermal history: the current is switched on at the sweep's start
// (cold IRED), each pose takes `move_s` of motion, then the bracket's frames follow each other
// (exposure + readout).
class SweepRenderer {
 public:
  SweepRenderer(const sim::RigPhysics& physics, std::uint64_t seed)
      : physics_(physics), renderer_(physics), seed_(seed) {}

  // With `recoverer`, every bracket's frames (reference first) also go to it as one stack.
  // refine: when set, each frame's moments (the reference's too, as in the app) are replaced by the blob fit with this
  // model's calibrated blur (RefineWithBlobFit).
  std::vector<Bracket> Run(const std::vector<Pose>& poses, const std::vector<double>& t_ms,
                           const FeatureOptions& fo, ResponseRecoverer* recoverer = nullptr,
                           const CalibrationModel* refine = nullptr) {
    std::vector<sim::CurrentStep> history;
    double now = 0.0;
    double current = -1.0;
    std::vector<Bracket> out;
    const int side = 192;
    const cv::Point origin(physics_.sensor.width_px / 2 - side / 2,
                           physics_.sensor.height_px / 2 - side / 2);
    cv::Mat frame(side, side, CV_16UC1);
    for (const Pose& p : poses) {
      if (p.bias_ma != current) {
        history.push_back({now, p.bias_ma});
        current = p.bias_ma;
      }
      now += 1.5;  // motion and settling
      Bracket b;
      b.pose = p;
      b.t_ms = t_ms;
      std::vector<double> all = {kTRefMs};
      all.insert(all.end(), t_ms.begin(), t_ms.end());
      std::vector<cv::Mat> stack;
      std::vector<double> stack_us;
      for (size_t k = 0; k < all.size(); ++k) {
        sim::FrameConditions c =
            sim::StaticConditions(p.d_mm, p.theta_deg, 0.0, p.bias_ma, all[k] * 1e-3);
        c.junction_rise_k = renderer_.scene().JunctionRiseK(history, now + 0.5 * all[k] * 1e-3);
        if (k == 0) b.rise_k = c.junction_rise_k;
        renderer_.Render(c, ++frame_index_ + seed_ * 1000003ull, sim::PixelFormat::kMono12, origin,
                         frame);
        Features f = ComputeFeatures(frame, 12, fo);
        if (keep_ != nullptr && k > 0) keep_->push_back({frame.clone(), 12, f, 0.0});
        if (refine != nullptr) RefineWithBlobFit(frame, 12, *refine, &f);  // every frame, as the app
        if (recoverer != nullptr) {
          stack.push_back(frame.clone());
          stack_us.push_back(all[k] * 1000.0);
        }
        if (k == 0) {
          b.reference = f;
        } else {
          b.measurements.push_back(f);
        }
        now += all[k] * 1e-3 + physics_.camera.readout_ms * 1e-3;
      }
      if (recoverer != nullptr) recoverer->AddStack(stack, stack_us, fo);
      out.push_back(std::move(b));
    }
    return out;
  }
  // Keeps every measurement frame of the next runs (frame and features; blur left 0).
  void KeepFrames(std::vector<CrosstalkFrame>* keep) { keep_ = keep; }
  double JunctionSteadyK(double bias_ma) const {
    const auto& e = physics_.emitter;
    return e.thermal_resistance_k_per_w * bias_ma * 1e-3 * e.forward_voltage_v;
  }

 private:
  sim::RigPhysics physics_;
  sim::Renderer renderer_;
  std::uint64_t seed_;
  std::uint64_t frame_index_ = 0;
  std::vector<CrosstalkFrame>* keep_ = nullptr;
};

struct Row {
  Pose pose;
  double dt_ms;  // 0 = joint over the bracket
  double d_mm, theta_deg;
  bool ok;
  double d_std = 0.0;
};

double Percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const double pos = q * (v.size() - 1);
  const size_t i = static_cast<size_t>(pos);
  const double f = pos - i;
  return i + 1 < v.size() ? v[i] * (1 - f) + v[i + 1] * f : v[i];
}

struct Figures {
  int n = 0, failed = 0;
  double med = 0, p95 = 0, max = 0;  // relative distance error, %
  double th_med = 0, th_max = 0;     // |theta error| for theta >= 15, deg
  double shift = 0;                  // current shift, %
  double disp = 0;                   // largest sd over repetitions, mm
  Pose worst_theta{0, 0, 0, 0};      // pose of the largest theta error (theta >= 15)
};

Figures Summarise(const std::vector<Row>& rows, bool theta_reported) {
  Figures f;
  std::vector<double> err, th;
  std::map<std::tuple<double, double, double>, std::map<double, std::vector<double>>> by_pose;
  for (const Row& r : rows) {
    if (!r.ok) {
      ++f.failed;
      continue;
    }
    if (r.pose.d_mm < 1499 || r.pose.d_mm > 2901 || r.pose.theta_deg > 30.01) continue;
    ++f.n;
    err.push_back(100.0 * std::abs(r.d_mm / r.pose.d_mm - 1.0));
    if (theta_reported && r.pose.theta_deg >= 15) {
      th.push_back(std::abs(r.theta_deg - r.pose.theta_deg));
      if (th.back() >= *std::max_element(th.begin(), th.end())) f.worst_theta = r.pose;
    }
    by_pose[{r.pose.d_mm, r.pose.theta_deg, r.dt_ms}][r.pose.bias_ma].push_back(r.d_mm);
  }
  f.med = Percentile(err, 0.5);
  f.p95 = Percentile(err, 0.95);
  f.max = err.empty() ? 0 : *std::max_element(err.begin(), err.end());
  f.th_med = Percentile(th, 0.5);
  f.th_max = th.empty() ? 0 : *std::max_element(th.begin(), th.end());
  for (const auto& [key, currents] : by_pose) {
    std::vector<double> means;
    for (const auto& [i, v] : currents) {
      double m = 0;
      for (double x : v) m += x / v.size();
      means.push_back(m);
      if (v.size() > 2) {
        double s = 0;
        for (double x : v) s += (x - m) * (x - m);
        f.disp = std::max(f.disp, std::sqrt(s / (v.size() - 1)));
      }
    }
    if (means.size() > 1) {
      const auto [lo, hi] = std::minmax_element(means.begin(), means.end());
      f.shift = std::max(f.shift, 100.0 * (*hi - *lo) / std::get<0>(key));
    }
  }
  return f;
}

void Print(const char* experiment, const char* method, const Figures& f, bool theta_reported) {
  std::printf("  %-8s %-16s n=%4d fail=%3d  rel.err%% med %.3f p95 %.3f max %.3f", experiment,
              method, f.n, f.failed, f.med, f.p95, f.max);
  if (theta_reported) {
    std::printf("  theta>=15 med %.2f max %.2f deg (at %g mm %g deg)", f.th_med, f.th_max,
                f.worst_theta.d_mm, f.worst_theta.theta_deg);
  }
  std::printf("  shift %.3f%%  disp %.2f mm\n", f.shift, f.disp);
}

std::vector<CalibrationSample> Samples(const std::vector<Bracket>& brackets) {
  std::vector<CalibrationSample> out;
  for (const Bracket& b : brackets) {
    for (size_t k = 0; k < b.measurements.size(); ++k) {
      CalibrationSample s;
      s.reference = b.reference;
      s.measurement = b.measurements[k];
      s.t_ref_ms = kTRefMs;
      s.t_ms = b.t_ms[k];
      s.bias_ma = b.pose.bias_ma;
      s.d_mm = b.pose.d_mm;
      s.theta_deg = b.pose.theta_deg;
      out.push_back(s);
    }
  }
  return out;
}

struct Pipeline {
  std::string name;
  bool recover_response = false;  // features with the response recovered from the calibration
  FeatureOptions features;
  FitOptions fit;
  EstimateOptions estimate;
  bool per_exposure = false;  // report each t_n (the paper) rather than the joint estimate
  bool blob_fit = false;      // validation frames' moments from the blob fit (estimator/blob_fit.h)
  CalibrationModel model;
};

struct Methods {
  std::map<std::string, std::vector<Row>> rows;
  std::map<std::string, std::pair<int, int>> health;  // pipeline -> (assessed, flagged)
};

// How well the blur measured on each frame agrees with the calibrated blur: mean and sd of the
// per-frame departure (px^2) and of its z-score.
void PrintBlurCheck(const CalibrationModel& model, const std::vector<Bracket>& brackets,
                    const char* experiment) {
  double s = 0, ss = 0, z = 0, zz = 0, zmax = 0;
  int n = 0;
  const BlurCalibration& cal = model.blur_calibration;
  if (!cal.fitted()) return;
  for (const Bracket& b : brackets) {
    for (const Features& f : b.measurements) {
      if (!f.Usable() || !std::isfinite(f.blur_var_px2)) continue;
      const double r = f.blur_var_px2 - cal.BlurVarPx2(b.pose.d_mm);
      s += r;
      ss += r * r;
      z += r / cal.NoisePx2(b.pose.d_mm);
      zz += std::pow(r / cal.NoisePx2(b.pose.d_mm), 2);
      zmax = std::max(zmax, std::fabs(r / cal.NoisePx2(b.pose.d_mm)));
      ++n;
    }
  }
  if (n == 0) return;
  std::printf("  %-8s blur per frame vs calibrated: mean %+.4f sd %.4f px^2; z mean %+.2f sd %.2f "
              "max |z| %.2f (%d frames; calibration sd at 1 m %.4f px^2, exponent %.2f)\n",
              experiment, s / n, std::sqrt(std::max(0.0, ss / n - (s / n) * (s / n))), z / n,
              std::sqrt(std::max(0.0, zz / n - (z / n) * (z / n))), zmax, n, cal.noise_at_1m_px2,
              cal.noise_exponent);
}

// Calibration health of one bracket's joint estimate (estimator/health.h).
void CountHealth(const Pipeline& pl, const Bracket& b, double d_mm, Methods* m) {
  std::vector<const Features*> frames;
  for (const Features& f : b.measurements) frames.push_back(&f);
  const HealthCheck h = CheckHealth(pl.model, d_mm, frames);
  auto& counts = m->health[pl.name];
  counts.first += h.assessed ? 1 : 0;
  counts.second += h.flagged ? 1 : 0;
}

void Estimate(const Pipeline& pl, const std::vector<Bracket>& brackets, Methods* m,
              bool with_baselines, double nominal_ma) {
  for (const Bracket& b : brackets) {
    if (!b.reference.Usable()) {
      m->rows[pl.name].push_back({b.pose, 0, 0, 0, false});
      continue;
    }
    const BracketEstimate be =
        EstimateBracket(pl.model, b.reference, kTRefMs, b.measurements, b.t_ms, pl.estimate);
    if (pl.per_exposure) {
      for (size_t k = 0; k < b.t_ms.size(); ++k) {
        const DistanceEstimate& e = be.per_exposure[k];
        m->rows[pl.name].push_back({b.pose, b.t_ms[k] - kTRefMs, e.d_mm, e.theta_deg, true});
      }
    } else {
      m->rows[pl.name].push_back(
          {b.pose, 0, be.joint.d_mm, be.joint.theta_deg, true, be.joint.d_std_mm});
      CountHealth(pl, b, be.joint.d_mm, m);
    }
    if (!with_baselines) continue;
    const I0DependentEstimate di =
        EstimateI0Dependent(pl.model, b.reference, kTRefMs, b.measurements, b.t_ms, nominal_ma);
    m->rows["i0_dependent"].push_back({b.pose, 0, di.d_mm, di.theta_deg, di.valid});
    double g = 0;
    int ng = 0;
    for (const Features& f : b.measurements) {
      const GeometricEstimate ge = EstimateGeometric(pl.model, f);
      if (ge.valid) {
        g += ge.d_mm;
        ++ng;
      }
    }
    m->rows["geometric"].push_back({b.pose, 0, ng ? g / ng : 0, 0, ng > 0});
  }
}

struct Experiment {
  const char* name;
  std::vector<Pose> poses;
  std::vector<double> t_ms;
};

// The lens PSF that changes the total blur (PSF and defocus) at 2250 mm, the middle of Table 3,
// by the relative `change`: what a touched focus ring or a warmed lens does after calibration.
sim::RigPhysics WithBlurChanged(const sim::RigPhysics& physics, double change) {
  const sim::Scene scene(physics);
  const double total = scene.BlurSigmaPx(2250.0) * (1.0 + change);
  const double coc = scene.CircleOfConfusionPx(2250.0);
  sim::RigPhysics out = physics;
  out.optics.psf_sigma_px = std::sqrt(std::max(0.0, total * total - coc * coc / 16.0));
  return out;
}

// Validation on a rig whose blur changed after calibration: the default pipeline's health flags
// and distance errors (the model stays the unchanged rig's).
void RunBlurChange(const sim::RigPhysics& physics, std::uint64_t seed, double change,
                   const std::vector<Pipeline>& pipelines, const std::vector<Experiment>& experiments) {
  const sim::RigPhysics changed = WithBlurChanged(physics, change);
  std::printf("blur changed by %+.0f%% after calibration (lens PSF %.3f -> %.3f px):\n", 100 * change,
              physics.optics.psf_sigma_px, changed.optics.psf_sigma_px);
  for (const Pipeline& pl : pipelines) {
    if (pl.name != "default") continue;
    for (const Experiment& ex : experiments) {
      Methods m;
      SweepRenderer sr(changed, seed + 100);
      Estimate(pl, sr.Run(ex.poses, ex.t_ms, pl.features, nullptr, pl.blob_fit ? &pl.model : nullptr),
               &m, false, 500.0);
      const auto counts = m.health[pl.name];
      Print(ex.name, "default", Summarise(m.rows[pl.name], true), true);
      std::printf("  %-8s default          health: %d of %d estimates flagged\n", ex.name,
                  counts.second, counts.first);
    }
  }
}

std::vector<double> Range(double a, double b, double step) {
  std::vector<double> v;
  for (double x = a; x <= b + 1e-9; x += step) v.push_back(x);
  return v;
}

// The blob fit's split of the calibrated blur (optics before the pixels, crosstalk after them),
// fitted on calibration frames as `irdist calibrate` does (app/processing/recording_fit.cc,
// CalibrateCrosstalk): 32 measurement frames over the calibrated distances and angles.
void CalibrateBlurSplit(const sim::RigPhysics& physics, std::uint64_t seed, Pipeline* pl) {
  std::vector<Pose> poses;
  for (double d : Range(1500, 3000, 500))
    for (double th : {0.0, 10.0, 20.0, 30.0}) poses.push_back({d, th, 500.0, 0});
  SweepRenderer sr(physics, seed + 17);
  std::vector<CrosstalkFrame> frames;
  sr.KeepFrames(&frames);
  sr.Run(poses, {34, 36}, pl->features);
  for (CrosstalkFrame& f : frames) {
    f.blur_var_px2 = BlobFitBlurVarPx2(pl->model, f.features);
    f.d_mm = pl->model.geometric.DistanceMm(f.features.moment_major_var_px2);
  }
  const BlurSplit split = FitBlurSplit(frames);
  pl->model.blur_calibration.crosstalk_var_px2 = split.crosstalk_var_px2;
  pl->model.blur_calibration.crosstalk_lattice_share = split.crosstalk_lattice_share;
  pl->model.blur_calibration.fit_offset_px2 = split.blur_offset_px2;
  pl->model.blur_calibration.fit_offset_u_px2 = split.blur_offset_u_px2;
  std::printf("calibration %-10s blur split: %.4f px^2 after the pixels (crosstalk), the fit's "
              "blur %+.4f %+.4f (1000 / d) px^2 from the cumulants', %d frames\n",
              pl->name.c_str(), split.crosstalk_var_px2, split.blur_offset_px2,
              split.blur_offset_u_px2, split.frames);
}

// Per angle of Fig. 14: sd of d and of theta over the repetitions, and the mean error, for the
// methods that estimate from the whole bracket.
void PrintDispersion(const Methods& m) {
  for (const auto& [name, rows] : m.rows) {
    if (name == "paper") continue;
    std::map<double, std::vector<const Row*>> by_theta;
    for (const Row& r : rows)
      if (r.ok) by_theta[r.pose.theta_deg].push_back(&r);
    std::printf("  fig14    %-16s per theta: sd d / sd theta / mean theta err:", name.c_str());
    for (const auto& [th, v] : by_theta) {
      double md = 0, mt = 0;
      for (const Row* r : v) md += r->d_mm / v.size(), mt += r->theta_deg / v.size();
      double sd = 0, st = 0;
      for (const Row* r : v)
        sd += (r->d_mm - md) * (r->d_mm - md), st += (r->theta_deg - mt) * (r->theta_deg - mt);
      const double k = v.size() > 1 ? 1.0 / (v.size() - 1) : 0.0;
      std::printf("  %g: %.2f mm / %.2f / %+.2f deg", th, std::sqrt(sd * k), std::sqrt(st * k),
                  mt - th);
    }
    std::printf("\n");
    // The outliers of the goal row: brackets with |theta error| > 2 deg or d off its true
    // value by more than 4 of its own standard errors, per theta.
    std::printf("  fig14    %-16s outliers (|theta err| > 2 deg or |d err| > 4 se):", name.c_str());
    for (const auto& [th, v] : by_theta) {
      int outliers = 0;
      for (const Row* r : v) {
        const bool far_d = r->d_std > 0.0 && std::fabs(r->d_mm - r->pose.d_mm) > 4.0 * r->d_std;
        outliers += std::fabs(r->theta_deg - th) > 2.0 || far_d;
      }
      std::printf("  %g: %d of %zu", th, outliers, v.size());
    }
    std::printf("\n");
  }
}

// theta0 from a second-moment matrix (xx, yy, xy) with the blur variance `beta` removed.
double ThetaFromMoments(double xx, double yy, double xy, double beta) {
  const double tr = xx + yy;
  const double root = std::sqrt(std::max(0.0, 0.25 * (xx - yy) * (xx - yy) + xy * xy));
  const double major = 0.5 * tr + root - beta, minor = 0.5 * tr - root - beta;
  if (!(major > 0)) return 0;
  return std::acos(std::clamp(std::sqrt(std::max(0.0, minor) / major), 0.0, 1.0)) * 180 / M_PI;
}

// Dispersion and bias of theta0 variants over repeated frames of static poses (8 ms reference,
// 35 ms measurement), beside the Cramer-Rao bound.
void ThetaProbe(const sim::RigPhysics& physics, std::uint64_t seed) {
  const double beta = physics.optics.psf_sigma_px * physics.optics.psf_sigma_px + 1.0 / 12;
  const double steady = physics.emitter.thermal_resistance_k_per_w * 0.5 *
                        physics.emitter.forward_voltage_v;
  sim::Renderer r(physics);
  const int side = 192;
  const cv::Point origin(physics.sensor.width_px / 2 - side / 2,
                         physics.sensor.height_px / 2 - side / 2);
  cv::Mat frame(side, side, CV_16UC1);
  for (double d : {2100.0, 2900.0}) {
    for (double th : {15.0, 20.0, 30.0}) {
      const CrbResult crb = ComputeCrb(physics, {d, th, 500.0, steady, {kTRefMs, 35.0}});
      std::printf("%g mm %g deg: CRB theta %.3f deg\n", d, th, crb.theta_sd_deg);
      // > 0: threshold moments at that fraction; < 0: aperture moments with that margin (px).
      std::vector<double> fractions = {0.02, -2.0, -3.0, -5.0};
      std::vector<std::vector<double>> meas(fractions.size() * 3);
      for (int rep = 0; rep < 60; ++rep) {
        for (size_t fi = 0; fi < fractions.size(); ++fi) {
          FeatureOptions fo;
          if (fractions[fi] > 0) {
            fo.moment_method = MomentMethod::kThreshold;
            fo.moment_threshold_fraction = fractions[fi];
          } else {
            fo.moment_method = MomentMethod::kAperture;
            fo.aperture_margin_px = -fractions[fi];
          }
          Features f[2];
          for (int k = 0; k < 2; ++k) {
            sim::FrameConditions c = sim::StaticConditions(d, th, 0, 500, (k ? 35.0 : kTRefMs) * 1e-3);
            c.junction_rise_k = steady;
            r.Render(c, seed * 1000003ull + rep * 2 + k, sim::PixelFormat::kMono12, origin, frame);
            f[k] = ComputeFeatures(frame, 12, fo);
          }
          auto mat = [](const Features& x, double* xx, double* yy, double* xy) {
            const double a = x.ellipse_moments.angle_deg * M_PI / 180;
            const double l1 = x.moment_major_var_px2, l2 = x.moment_minor_var_px2;
            *xx = l1 * std::cos(a) * std::cos(a) + l2 * std::sin(a) * std::sin(a);
            *yy = l1 * std::sin(a) * std::sin(a) + l2 * std::cos(a) * std::cos(a);
            *xy = (l1 - l2) * std::sin(a) * std::cos(a);
          };
          double m[2][3];
          for (int k = 0; k < 2; ++k) mat(f[k], &m[k][0], &m[k][1], &m[k][2]);
          meas[fi * 3].push_back(ThetaFromMoments(m[1][0], m[1][1], m[1][2], beta));
          const double w0 = f[0].f00 - f[0].background * f[0].roi_area_px;
          const double w1 = f[1].f00 - f[1].background * f[1].roi_area_px;
          double c[3];
          for (int j = 0; j < 3; ++j) c[j] = (w0 * m[0][j] + w1 * m[1][j]) / (w0 + w1);
          meas[fi * 3 + 1].push_back(ThetaFromMoments(c[0], c[1], c[2], beta));
          meas[fi * 3 + 2].push_back(ThetaFromMoments(m[0][0], m[0][1], m[0][2], beta));
        }
      }
      for (size_t v = 0; v < meas.size(); ++v) {
        double mean = 0, sd = 0;
        for (double x : meas[v]) mean += x / meas[v].size();
        for (double x : meas[v]) sd += (x - mean) * (x - mean) / (meas[v].size() - 1);
        std::printf("  %s %.2f %-10s bias %+.3f sd %.3f\n", fractions[v / 3] > 0 ? "thr" : "ap.margin",
                    std::abs(fractions[v / 3]),
                    v % 3 == 0 ? "35ms" : v % 3 == 1 ? "combined" : "8ms", mean - th,
                    std::sqrt(sd));
      }
      // EllipseMethod::kModelFit: theta0 of the fitted blurred disc, per frame.
      std::vector<double> fit_theta[2], fit_blur;
      FeatureOptions fo;
      fo.ellipse_method = EllipseMethod::kModelFit;
      for (int rep = 0; rep < 60; ++rep) {
        for (int k = 0; k < 2; ++k) {
          sim::FrameConditions c = sim::StaticConditions(d, th, 0, 500, (k ? 35.0 : kTRefMs) * 1e-3);
          c.junction_rise_k = steady;
          r.Render(c, seed * 1000003ull + rep * 2 + k, sim::PixelFormat::kMono12, origin, frame);
          const Features f = ComputeFeatures(frame, 12, fo);
          fit_theta[k].push_back(f.ellipse_model.theta0_deg);
          if (k == 1) fit_blur.push_back(f.model_blur_px);
        }
      }
      for (int k = 1; k >= 0; --k) {
        double mean = 0, sd = 0, blur = 0;
        for (double x : fit_theta[k]) mean += x / fit_theta[k].size();
        for (double x : fit_theta[k]) sd += (x - mean) * (x - mean) / (fit_theta[k].size() - 1);
        for (double x : fit_blur) blur += x / fit_blur.size();
        std::printf("  model fit  %-10s bias %+.3f sd %.3f (fitted blur %.3f px)\n",
                    k ? "35ms" : "8ms", mean - th, std::sqrt(sd), blur);
      }
    }
  }
}

int Main(int argc, char** argv) {
  std::string rig = std::string(IRDIST_SOURCE_DIR) + "/recipes/rigs/virtual.yaml";
  std::uint64_t seed = 7;
  bool quick = false;
  bool verbose = false;
  bool crb_only = false;
  bool theta_probe = false;
  bool theta_variants = false;
  bool model_fit = false;  // pipeline model_fit: theta0 from EllipseMethod::kModelFit
  double nonlinearity = -1.0;  // --nonlinearity A: the rig's sensor nonlinearity replaced by A
  std::vector<double> blur_changes;  // --blur-change X: validate with the blur changed by X
  bool only_default = false;         // --only-default: the default and fixed_blur pipelines only
  std::string dump_theta;  // CSV of the calibration frames' moments and theta0 (default pipeline)
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--rig") && i + 1 < argc)
      rig = argv[++i];
    else if (!std::strcmp(argv[i], "--seed") && i + 1 < argc)
      seed = std::stoull(argv[++i]);
    else if (!std::strcmp(argv[i], "--nonlinearity") && i + 1 < argc)
      nonlinearity = std::stod(argv[++i]);
    else if (!std::strcmp(argv[i], "--quick"))
      quick = true;
    else if (!std::strcmp(argv[i], "--theta-variants"))
      theta_variants = true;
    else if (!std::strcmp(argv[i], "--model-fit"))
      model_fit = true;
    else if (!std::strcmp(argv[i], "--theta-probe"))
      theta_probe = true;
    else if (!std::strcmp(argv[i], "--blur-change") && i + 1 < argc)
      blur_changes.push_back(std::stod(argv[++i]));
    else if (!std::strcmp(argv[i], "--only-default"))
      only_default = true;
    else if (!std::strcmp(argv[i], "--crb-only"))
      crb_only = true;
    else if (!std::strcmp(argv[i], "--help")) {
      std::printf(
          "irdist_accuracy_study [--rig FILE] [--seed N] [--quick] [--verbose] [--crb-only]\n"
          "  [--nonlinearity A] (the sensor's y = x - A x^2 / x_max instead of the rig's)\n"
          "  [--radiometric-weight W]... [--theta-degree N]... [--dump-theta CSV]\n"
          "  (pipeline theta_cal: the default with the calibrated theta correction;\n"
          "   --theta-degree N adds the default with a correction of total degree N;\n"
          "   --model-fit adds pipeline model_fit: theta0 of EllipseMethod::kModelFit;\n"
          "   --theta-variants adds theta_bracket (ThetaSource::kBracketMoments) and threshold\n"
          "   (MomentMethod::kThreshold); --theta-probe prints theta0's bias per pose and method;\n"
          "   --blur-change X (repeatable) validates again with the blur changed by X (0.15 = 15%%)\n"
          "   after calibration and prints the health flags; --only-default keeps the default\n"
          "   and fixed_blur (the geometric model with one blur for every distance))\n");
      return 0;
    } else if (!std::strcmp(argv[i], "--verbose"))
      verbose = true;
    else if (!std::strcmp(argv[i], "--dump-theta") && i + 1 < argc)
      dump_theta = argv[++i];
    else if (!std::strcmp(argv[i], "--radiometric-weight") ||
             !std::strcmp(argv[i], "--theta-degree"))
      ++i;
  }
  sim::RigPhysics physics = sim::LoadRigPhysics(rig);
  if (nonlinearity >= 0.0) physics.sensor.nonlinearity = nonlinearity;
  std::printf("rig %s, seed %llu, sensor nonlinearity %g\n", rig.c_str(),
              static_cast<unsigned long long>(seed), physics.sensor.nonlinearity);
  const auto t0 = std::chrono::steady_clock::now();

  // Exposure linearity of the renderer and sensor (the acquisition report of 4.05x at 36 ms):
  // frame signal above the black level, 36 ms vs 8 ms, at a fixed junction rise and across a
  // cold start (the current switched on just before the 8 ms frame).
  {
    sim::Renderer r(physics);
    const double black = physics.sensor.black_level_dn;
    auto frame_signal = [&](double t_ms, double rise_k, std::uint64_t index) {
      sim::FrameConditions c = sim::StaticConditions(1500, 0, 0, 500, t_ms * 1e-3);
      c.junction_rise_k = rise_k;
      const cv::Mat f = r.Render(c, index, sim::PixelFormat::kMono12);
      const cv::Rect w(physics.sensor.width_px / 2 - 40, physics.sensor.height_px / 2 - 40, 80, 80);
      return cv::sum(f(w))[0] - black * w.area();
    };
    const double steady = 20.0 * 0.5 * 1.6;
    const double s8 = frame_signal(8, steady, 1), s36 = frame_signal(36, steady, 2);
    const double cold36 = frame_signal(36, 0.0, 3);
    std::printf(
        "linearity: signal(36 ms)/signal(8 ms) = %.4f (expected 4.5000) at a steady "
        "junction; %.4f if the 8 ms frame saw a cold junction and the 36 ms a hot one\n",
        s36 / s8, s36 / cold36 * 4.5);
    sim::PoseState pose;
    pose.slide_mm = 1500;
    pose.bias_ma = 500;
    std::printf("  1500 mm, 500 mA, 36 ms, steady junction: %s\n",
                r.Describe(pose, 0.036, sim::PixelFormat::kMono12, steady).BriefReport().c_str());
    // Noise-free: the mean signal electrons of the scene, and the same with 20 frames averaged.
    auto mean_signal = [&](double t_ms) {
      sim::FrameConditions c = sim::StaticConditions(1500, 0, 0, 500, t_ms * 1e-3);
      c.junction_rise_k = steady;
      return cv::sum(r.Signal(c).electrons)[0];
    };
    double a8 = 0, a36 = 0;
    for (int k = 0; k < 20; ++k) {
      a8 += frame_signal(8, steady, 100 + k);
      a36 += frame_signal(36, steady, 200 + k);
    }
    std::printf("  noise-free scene signal ratio %.5f; mean of 20 noisy frames each %.4f\n",
                mean_signal(36) / mean_signal(8), a36 / a8);
  }

  // The statistical limit: Cramer-Rao bound at 2.7 m, 500 mA, steady junction.
  {
    const double steady = physics.emitter.thermal_resistance_k_per_w * 0.5 *
                           physics.emitter.forward_voltage_v;
    std::printf("Cramer-Rao bound (unknowns ln I0, theta, x, y, d; EMVA noise):\n");
    for (double th : {0.0, 10.0, 20.0, 30.0}) {
      CrbConditions c{2700.0, th, 500.0, steady, {kTRefMs, 35.0}};
      const CrbResult pair = ComputeCrb(physics, c);
      c.exposures_ms = {kTRefMs, 30, 32, 34, 36, 38, 40};
      const CrbResult bracket = ComputeCrb(physics, c);
      std::printf("  2700 mm theta %2g: pair (8, 35 ms): %s\n", th, pair.BriefReport().c_str());
      std::printf("                    bracket (8; 30..40 ms): %s\n",
                  bracket.BriefReport().c_str());
    }
    std::printf("  scaling with d (theta 0, pair 8/35 ms):");
    double prev_d = 0, prev_sd = 0;
    for (double d : {1500.0, 2100.0, 2700.0}) {
      const CrbResult r = ComputeCrb(physics, {d, 0.0, 500.0, steady, {kTRefMs, 35.0}});
      std::printf(" %g mm %.2f mm", d, r.d_sd_mm);
      if (prev_d > 0) std::printf(" (exponent %.2f)", std::log(r.d_sd_mm / prev_sd) / std::log(d / prev_d));
      prev_d = d;
      prev_sd = r.d_sd_mm;
    }
    std::printf("\n");
  }
  if (crb_only) return 0;
  if (theta_probe) {
    ThetaProbe(physics, seed);
    return 0;
  }

  // Pipelines.
  std::vector<Pipeline> pipelines(3);
  std::vector<double> extra_weights;
  for (int i = 1; i < argc; ++i)
    if (!std::strcmp(argv[i], "--radiometric-weight") && i + 1 < argc)
      extra_weights.push_back(std::stod(argv[++i]));
  for (double w : extra_weights) {
    Pipeline pl;
    char name[32];
    std::snprintf(name, sizeof(name), "fused_w%.3g", w);
    pl.name = name;
    pl.estimate.radiometric_weight = w;
    pipelines.push_back(pl);
  }
  pipelines[0].name = "paper";
  pipelines[0].features = PaperFeatureOptions();
  pipelines[0].fit = PaperFitOptions();
  pipelines[0].estimate = PaperEstimateOptions();
  pipelines[0].per_exposure = true;
  pipelines[1].name = "default";
  pipelines[2].name = "alg1_joint";  // default fit, Algorithm 1 jointly over t_n, better theta0
  pipelines[2].estimate.method = EstimateMethod::kAlgorithm1;
  {
    Pipeline pl;
    pl.name = "theta_cal";  // default with the calibrated theta correction (fit.h)
    pl.estimate.theta_correction = true;
    pipelines.push_back(pl);
  }
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--theta-degree") && i + 1 < argc) {
      Pipeline pl;
      pl.fit.theta_correction_degree = std::stoi(argv[++i]);
      pl.estimate.theta_correction = true;
      pl.name = "theta_cal_deg" + std::to_string(pl.fit.theta_correction_degree);
      pipelines.push_back(pl);
    }
  }
  {
    // The default estimator on features whose every pixel is linearised by the camera response
    // recovered from the calibration's own brackets (ResponseScope::kAllPixels).
    Pipeline pl;
    pl.name = "response";
    pl.recover_response = true;
    pipelines.push_back(pl);
  }
  {
    // The earlier default: the geometric model with one blur for every distance.
    Pipeline pl;
    pl.name = "fixed_blur";
    pl.fit.geometric_blur_varies_with_distance = false;
    pipelines.push_back(pl);
  }
  {
    // The default with the blob's size and orientation from the likelihood fit with the
    // calibrated blur (estimator/blob_fit.h) instead of the second moments.
    Pipeline pl;
    pl.name = "blob_fit";
    pl.blob_fit = true;
    pipelines.push_back(pl);
  }
  if (only_default) {
    std::vector<Pipeline> kept;
    for (const Pipeline& pl : pipelines)
      if (pl.name == "default" || pl.name == "fixed_blur" || pl.name == "blob_fit")
        kept.push_back(pl);
    pipelines = kept;
  }
  if (model_fit) {
    Pipeline pl;
    pl.name = "model_fit";  // theta0 of the fitted blurred disc (features), no blur to remove
    pl.features.ellipse_method = EllipseMethod::kModelFit;
    pl.estimate.theta_source = ThetaSource::kFeatures;
    pipelines.push_back(pl);
  }
  if (theta_variants) {
    Pipeline pl;
    pl.name = "theta_bracket";  // theta0 from the signal-weighted moments of every frame
    pl.estimate.theta_source = ThetaSource::kBracketMoments;
    pipelines.push_back(pl);
    pl.name = "threshold";  // threshold moments (features and geometric baseline): the old default
    pl.estimate.theta_source = ThetaSource::kCalibratedBlur;
    pl.features.moment_method = MomentMethod::kThreshold;
    pipelines.push_back(pl);
    Pipeline fit_bracket;  // the blob fit, with theta from every frame's fitted shape (reference too)
    fit_bracket.name = "blob_fit_bracket";
    fit_bracket.blob_fit = true;
    fit_bracket.estimate.theta_source = ThetaSource::kBracketMoments;
    pipelines.push_back(fit_bracket);
  }

  // Calibration: Table 3.
  std::vector<Pose> calib;
  for (double d : Range(1500, 3000, 500))
    for (double th : Range(0, 35, 5))
      for (double i : {475.0, 500.0}) calib.push_back({d, th, i, 0});
  const std::vector<double> calib_t = {30, 32, 34, 36};

  for (Pipeline& pl : pipelines) {
    if (pl.recover_response) {
      SweepRenderer sr(physics, seed);
      ResponseRecoverer recoverer(12, ResponseOptions());
      sr.Run(calib, calib_t, pl.features, &recoverer);
      const ResponseRecovery recovery = recoverer.Solve();
      std::printf("calibration %-10s %s\n", pl.name.c_str(), recovery.BriefReport().c_str());
      pl.features.inverse_response = recovery.curve;
      pl.features.response_scope = ResponseScope::kAllPixels;
    }
    SweepRenderer sr(physics, seed);
    const auto brackets = sr.Run(calib, calib_t, pl.features);
    pl.model = Fit(Samples(brackets), pl.features, pl.fit);
    if (pl.blob_fit) {
      // As `irdist calibrate` (app/processing/recording_fit.cc): the split, then the models fitted again on the
      // blob fit's own sizes of the calibration frames.
      CalibrateBlurSplit(physics, seed, &pl);
      SweepRenderer again(physics, seed);
      const BlurCalibration blur = pl.model.blur_calibration;
      pl.model = Fit(Samples(again.Run(calib, calib_t, pl.features, nullptr, &pl.model)),
                     pl.features, pl.fit);
      pl.model.blur_calibration = blur;
    }
    if (!dump_theta.empty() && pl.name == "default") {
      // Per calibration frame: true pose, moment variances, theta0 without / with correction.
      FILE* out = std::fopen(dump_theta.c_str(), "w");
      if (out != nullptr) {
        std::fprintf(out, "d_mm,theta_deg,bias_ma,t_ms,major_px2,minor_px2,peak,raw_deg,cal_deg\n");
        ThetaCorrection none;
        for (const CalibrationSample& s : Samples(brackets)) {
          const Features& m = s.measurement;
          std::fprintf(out, "%g,%g,%g,%g,%.9g,%.9g,%.6g,%.6f,%.6f\n", s.d_mm, s.theta_deg,
                       s.bias_ma, s.t_ms, m.moment_major_var_px2, m.moment_minor_var_px2, m.peak,
                       none.ThetaDeg(m.moment_major_var_px2, m.moment_minor_var_px2,
                                     pl.model.geometric),
                       pl.model.theta_correction.ThetaDeg(m.moment_major_var_px2,
                                                          m.moment_minor_var_px2,
                                                          pl.model.geometric));
        }
        std::fclose(out);
      }
    }
    if (verbose)
      std::printf("calibration %s:\n%s\n", pl.name.c_str(), pl.model.BriefReport().c_str());
    const FittedModel* fs = pl.model.Find(ModelKind::kFreeSigma);
    std::printf(
        "calibration %-10s free_sigma (%s) mean %.3f%% max %.3f%% cond %.2g; geometric mean "
        "%.3f%% max %.3f%%; blur variance %.3f px^2\n",
        pl.name.c_str(), ToString(fs->form), 100 * fs->summary.mean_relative_error,
        100 * fs->summary.max_relative_error, fs->summary.condition_number,
        100 * pl.model.geometric.summary.mean_relative_error,
        100 * pl.model.geometric.summary.max_relative_error, pl.model.geometric.beta_px2);
    const ThetaCorrection& tc = pl.model.theta_correction;
    if (tc.fitted()) {
      std::printf("  theta correction degree %d: %d frames, |theta error| mean %.3f max %.3f deg\n",
                  tc.degree, tc.summary.samples, tc.summary.mean_relative_error,
                  tc.summary.max_relative_error);
    }
  }

  // Validation grids.
  std::vector<Experiment> experiments;
  {
    Experiment e{"fig10", {}, Range(30, 40, 2)};
    for (double d : Range(1500, 2900, 200))
      for (double th : {0.0, 10.0, 20.0, 30.0})
        for (double i : {475.0, 500.0, 525.0}) e.poses.push_back({d, th, i, 0});
    experiments.push_back(e);
  }
  {
    Experiment e{"fig13", {}, {35}};
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> cur(500.0, 50.0);
    for (double d : {1700.0, 2300.0, 2900.0})
      for (double th : {10.0, 15.0, 20.0})
        for (int k = 0; k < 10; ++k)
          e.poses.push_back({d, th, std::clamp(cur(rng), 300.0, 650.0), k});
    experiments.push_back(e);
  }
  {
    Experiment e{"fig14", {}, {35}};
    for (double th : {0.0, 10.0, 20.0, 30.0})
      for (int k = 0; k < (quick ? 20 : 100); ++k) e.poses.push_back({2700, th, 500, k});
    experiments.push_back(e);
  }
  for (const Experiment& ex : experiments) {
    Methods m;
    for (size_t p = 0; p < pipelines.size(); ++p) {
      SweepRenderer sr(physics, seed + 100);
      const Pipeline& pl = pipelines[p];
      const auto brackets =
          sr.Run(ex.poses, ex.t_ms, pl.features, nullptr, pl.blob_fit ? &pl.model : nullptr);
      Estimate(pipelines[p], brackets, &m, pipelines[p].name == "default", 500.0);
      if (pipelines[p].name == "default") PrintBlurCheck(pipelines[p].model, brackets, ex.name);
    }
    std::printf("%s (%zu brackets, t_n", ex.name, ex.poses.size());
    for (double t : ex.t_ms) std::printf(" %g", t);
    std::printf(" ms):\n");
    for (const auto& [name, rows] : m.rows) {
      if (name == "default" && !m.rows["default"].empty()) {
        double sd = 0;
        for (const Row& r : rows) sd += r.d_std / rows.size();
        std::printf("  %-8s default mean standard error per estimate %.2f mm\n", ex.name, sd);
      }
      const bool th = name != "geometric";
      Print(ex.name, name.c_str(), Summarise(rows, th), th);
    }
    for (const auto& [name, counts] : m.health) {
      std::printf("  %-8s %-16s health: %d of %d estimates flagged\n", ex.name, name.c_str(),
                  counts.second, counts.first);
    }
    if (std::string(ex.name) == "fig14") PrintDispersion(m);
  }
  for (double change : blur_changes) RunBlurChange(physics, seed, change, pipelines, experiments);
  std::printf("elapsed %.1f s\n",
              std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  return 0;
}

}  // namespace
}  // namespace irdist

int main(int argc, char** argv) { return irdist::Main(argc, argv); }
