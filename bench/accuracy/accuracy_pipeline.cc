// The accuracy study's machinery (accuracy_pipeline.h): sweeps rendered with the IRED's thermal
// history, the pipelines built and calibrated on Table 3, every method's estimates per bracket,
// and the figures printed per experiment.
#include "bench/accuracy/accuracy_pipeline.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <tuple>
#include <vector>

#include "estimator/blur_level.h"
#include "estimator/edge_correction.h"
#include "estimator/estimate_baselines.h"
#include "estimator/health.h"
#include "estimator/psf_anisotropy.h"
#include "estimator/round_blob.h"

namespace irdist::accuracy {
namespace {

double Percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const double pos = q * (v.size() - 1);
  const size_t i = static_cast<size_t>(pos);
  const double f = pos - i;
  return i + 1 < v.size() ? v[i] * (1 - f) + v[i + 1] * f : v[i];
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

// Calibration health of one bracket's joint estimate (estimator/health.h).
void CountHealth(const Pipeline& pl, const Bracket& b, double d_mm, Methods* m) {
  std::vector<const Features*> frames;
  for (const Features& f : b.measurements) frames.push_back(&f);
  const HealthCheck h = CheckHealth(pl.model, d_mm, frames);
  auto& counts = m->health[pl.name];
  counts.first += h.assessed ? 1 : 0;
  counts.second += h.flagged ? 1 : 0;
}

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

// Calibration: Table 3's poses (1500..3000 mm, 0..35 deg, 475 and 500 mA) and exposures.
std::vector<Pose> CalibrationPoses() {
  std::vector<Pose> calib;
  for (double d : Range(1500, 3000, 500))
    for (double th : Range(0, 35, 5))
      for (double i : {475.0, 500.0}) calib.push_back({d, th, i, 0});
  return calib;
}

std::vector<double> CalibrationTMs() { return {30, 32, 34, 36}; }

// The optics' PSF anisotropy from the sweep's face-on frames' moments, into the model where it
// stands out of its noise and a lens can have it (estimator/psf_anisotropy.h SetPsfAnisotropy),
// as `irdist fit` does (app/processing/recording_fit.cc, CalibratePsfAnisotropy).
void CalibratePsfAnisotropy(const std::vector<Bracket>& brackets, Pipeline* pl) {
  std::vector<Features> face_on;
  for (const Bracket& b : brackets) {
    if (std::fabs(b.pose.theta_deg) > kPsfAnisotropyFaceOnDeg) continue;
    if (b.reference.Usable()) face_on.push_back(b.reference);
    for (const Features& f : b.measurements) {
      if (f.Usable()) face_on.push_back(f);
    }
  }
  const PsfAnisotropy psf = FitPsfAnisotropy(face_on);
  BlurCalibration& blur = pl->model.blur_calibration;
  const double least_optics_px2 =
      blur.LeastOpticsVarPx2(pl->model.ranges.d_min_mm, pl->model.ranges.d_max_mm);
  const bool kept = SetPsfAnisotropy(psf, least_optics_px2, &blur);
  std::printf(
      "calibration %-10s PSF anisotropy %+.4f +- %.4f, %+.4f +- %.4f px^2 from %d face-on "
      "frames: %s\n",
      pl->name.c_str(), psf.c_px2, psf.c_se_px2, psf.s_px2, psf.s_se_px2, psf.frames,
      kept ? "kept" : "the PSF taken as round");
}

// The PSF's anisotropy (CalibratePsfAnisotropy), then the blob fit's split of the calibrated blur
// (optics before the pixels, crosstalk after them), fitted on a Table 3 sweep's measurement frames
// as `irdist fit` does (app/processing/recording_fit.cc, CalibrateCrosstalk): their moments less
// that anisotropy, FitBlurSplit on 32 of them spread over the sweep (every k-th), then refined and
// its blur's level fitted on all of them (RefineBlurSplit), and the blob fit's edge correction
// learned on them (LearnEdgeCorrection).
void CalibrateBlurSplit(const sim::RigPhysics& physics, std::uint64_t seed, Pipeline* pl) {
  SweepRenderer sr(physics, seed + 17);
  std::vector<CrosstalkFrame> frames;
  sr.KeepFrames(&frames);
  CalibratePsfAnisotropy(sr.Run(CalibrationPoses(), CalibrationTMs(), pl->features), pl);
  const BlurCalibration& blur = pl->model.blur_calibration;
  for (CrosstalkFrame& f : frames) {
    RemovePsfAnisotropy(blur.psf_aniso_c_px2, blur.psf_aniso_s_px2, &f.features);
    f.blur_var_px2 = BlobFitBlurVarPx2(pl->model, f.features);
    f.d_mm = pl->model.geometric.DistanceMm(f.features.moment_major_var_px2);
  }
  const BlurSplit split =
      RefineBlurSplit(FitBlurSplit(SplitFramesOf(frames)), [&](const auto& use) {
        for (const CrosstalkFrame& f : frames) use(f);
      });
  SetSplit(split, &pl->model.blur_calibration);
  std::printf(
      "calibration %-10s blur split: %.4f px^2 after the pixels (crosstalk), the optics' "
      "edge's excess kurtosis %+.2f, the fit's blur %+.4f %+.4f u %+.4f u^2 (u = 1000 / d) px^2 "
      "from the cumulants', %d frames, refined on %d\n",
      pl->name.c_str(), split.crosstalk_var_px2, split.optics_excess, split.blur_offset_px2,
      split.blur_offset_u_px2, split.blur_offset_u2_px2, split.frames, split.level_frames);
  const EdgeCorrectionFit edge = LearnEdgeCorrection(
      [&](const auto& use) {
        for (const CrosstalkFrame& f : frames) use(f);
      },
      &pl->model.blur_calibration);
  std::printf("calibration %-10s edge correction: %s\n", pl->name.c_str(),
              DescribeEdgeCorrection(edge).c_str());
}

// paper, default, alg1_joint, one fused_w<W> per radiometric weight, theta_cal and one
// theta_cal_deg<N> per degree of the theta correction.
std::vector<Pipeline> EstimatorPipelines(const PipelineChoice& choice) {
  std::vector<Pipeline> pipelines(3);
  std::vector<double> extra_weights;
  for (const std::string& w : choice.radiometric_weights) extra_weights.push_back(std::stod(w));
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
  for (const std::string& degree : choice.theta_degrees) {
    Pipeline pl;
    pl.fit.theta_correction_degree = std::stoi(degree);
    pl.estimate.theta_correction = true;
    pl.name = "theta_cal_deg" + std::to_string(pl.fit.theta_correction_degree);
    pipelines.push_back(pl);
  }
  return pipelines;
}

// response, fixed_blur and blob_fit: the default estimator on other features or another blur model.
void AddFeaturePipelines(std::vector<Pipeline>* pipelines) {
  {
    // The default estimator on features whose every pixel is linearised by the camera response
    // recovered from the calibration's own brackets (ResponseScope::kAllPixels).
    Pipeline pl;
    pl.name = "response";
    pl.recover_response = true;
    pipelines->push_back(pl);
  }
  {
    // The earlier default: the geometric model with one blur for every distance.
    Pipeline pl;
    pl.name = "fixed_blur";
    pl.fit.geometric_blur_varies_with_distance = false;
    pipelines->push_back(pl);
  }
  {
    // The default with the blob's size and orientation from the likelihood fit with the
    // calibrated blur (estimator/blob_fit.h) instead of the second moments.
    Pipeline pl;
    pl.name = "blob_fit";
    pl.blob_fit = true;
    pipelines->push_back(pl);
  }
}

// Only the default, fixed_blur and blob_fit pipelines (--only-default).
void KeepDefaultPipelines(std::vector<Pipeline>* pipelines) {
  std::vector<Pipeline> kept;
  for (const Pipeline& pl : *pipelines)
    if (pl.name == "default" || pl.name == "fixed_blur" || pl.name == "blob_fit")
      kept.push_back(pl);
  *pipelines = kept;
}

// model_fit (--model-fit) and theta_bracket, threshold and blob_fit_bracket (--theta-variants).
void AddThetaPipelines(const PipelineChoice& choice, std::vector<Pipeline>* pipelines) {
  if (choice.model_fit) {
    Pipeline pl;
    pl.name = "model_fit";  // theta0 of the fitted blurred disc (features), no blur to remove
    pl.features.ellipse_method = EllipseMethod::kModelFit;
    pl.estimate.theta_source = ThetaSource::kFeatures;
    pipelines->push_back(pl);
  }
  if (choice.theta_variants) {
    Pipeline pl;
    pl.name = "theta_bracket";  // theta0 from the signal-weighted moments of every frame
    pl.estimate.theta_source = ThetaSource::kBracketMoments;
    pipelines->push_back(pl);
    pl.name = "threshold";  // threshold moments (features and geometric baseline): the old default
    pl.estimate.theta_source = ThetaSource::kCalibratedBlur;
    pl.features.moment_method = MomentMethod::kThreshold;
    pipelines->push_back(pl);
    Pipeline fit_bracket;  // the blob fit, with theta from every frame's fitted shape (reference too)
    fit_bracket.name = "blob_fit_bracket";
    fit_bracket.blob_fit = true;
    fit_bracket.estimate.theta_source = ThetaSource::kBracketMoments;
    pipelines->push_back(fit_bracket);
  }
}

// The camera response recovered from the calibration's brackets; the pipeline's features then
// linearise every pixel with it.
void RecoverResponse(const sim::RigPhysics& physics, std::uint64_t seed, Pipeline* pl) {
  SweepRenderer sr(physics, seed);
  ResponseRecoverer recoverer(12, ResponseOptions());
  sr.Run(CalibrationPoses(), CalibrationTMs(), pl->features, &recoverer);
  const ResponseRecovery recovery = recoverer.Solve();
  std::printf("calibration %-10s %s\n", pl->name.c_str(), recovery.BriefReport().c_str());
  pl->features.inverse_response = recovery.curve;
  pl->features.response_scope = ResponseScope::kAllPixels;
}

// As `irdist calibrate` (app/processing/recording_fit.cc): the split, then the models fitted again
// on the blob fit's own sizes of the calibration frames, each bracket's frames pooled under the
// round-blob rule as the estimate pools them.
void RefitWithBlobFit(const sim::RigPhysics& physics, std::uint64_t seed, Pipeline* pl) {
  CalibrateBlurSplit(physics, seed, pl);
  SweepRenderer again(physics, seed);
  const BlurCalibration blur = pl->model.blur_calibration;
  std::vector<Bracket> brackets =
      again.Run(CalibrationPoses(), CalibrationTMs(), pl->features, nullptr, &pl->model);
  for (Bracket& b : brackets) PoolBracket(&b.reference, &b.measurements);
  pl->model = Fit(Samples(brackets), pl->features, pl->fit);
  pl->model.blur_calibration = blur;
}

// Per calibration frame: true pose, moment variances, theta0 without / with correction.
void DumpTheta(const std::string& path, const Pipeline& pl, const std::vector<Bracket>& brackets) {
  FILE* out = std::fopen(path.c_str(), "w");
  if (out == nullptr) return;
  std::fprintf(out, "d_mm,theta_deg,bias_ma,t_ms,major_px2,minor_px2,peak,raw_deg,cal_deg\n");
  ThetaCorrection none;
  for (const CalibrationSample& s : Samples(brackets)) {
    const Features& m = s.measurement;
    std::fprintf(out, "%g,%g,%g,%g,%.9g,%.9g,%.6g,%.6f,%.6f\n", s.d_mm, s.theta_deg, s.bias_ma,
                 s.t_ms, m.moment_major_var_px2, m.moment_minor_var_px2, m.peak,
                 none.ThetaDeg(m.moment_major_var_px2, m.moment_minor_var_px2, pl.model.geometric),
                 pl.model.theta_correction.ThetaDeg(m.moment_major_var_px2,
                                                    m.moment_minor_var_px2, pl.model.geometric));
  }
  std::fclose(out);
}

// The calibration's figures: the free-sigma and geometric models' errors, the blur variance and
// the theta correction's residuals.
void PrintCalibration(const Pipeline& pl, bool verbose) {
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

}  // namespace

std::vector<Bracket> SweepRenderer::Run(const std::vector<Pose>& poses,
                                        const std::vector<double>& t_ms, const FeatureOptions& fo,
                                        ResponseRecoverer* recoverer,
                                        const CalibrationModel* refine) {
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

void PrintDispersion(const Methods& m) {
  for (const auto& [name, rows] : m.rows) {
    if (name == "paper") continue;
    std::map<double, std::vector<const Row*>> by_theta;
    for (const Row& r : rows)
      if (r.ok) by_theta[r.pose.theta_deg].push_back(&r);
    std::printf("  fig14    %-16s per theta: sd d / mean d err / sd theta / mean theta err:",
                name.c_str());
    for (const auto& [th, v] : by_theta) {
      double md = 0, mt = 0;
      for (const Row* r : v) md += r->d_mm / v.size(), mt += r->theta_deg / v.size();
      double sd = 0, st = 0;
      for (const Row* r : v)
        sd += (r->d_mm - md) * (r->d_mm - md), st += (r->theta_deg - mt) * (r->theta_deg - mt);
      const double k = v.size() > 1 ? 1.0 / (v.size() - 1) : 0.0;
      std::printf("  %g: %.2f / %+.2f mm / %.2f / %+.2f deg", th, std::sqrt(sd * k),
                  md - v.front()->pose.d_mm, std::sqrt(st * k), mt - th);
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

std::vector<Pipeline> BuildPipelines(const PipelineChoice& choice) {
  std::vector<Pipeline> pipelines = EstimatorPipelines(choice);
  AddFeaturePipelines(&pipelines);
  if (choice.only_default) KeepDefaultPipelines(&pipelines);
  AddThetaPipelines(choice, &pipelines);
  return pipelines;
}

void CalibratePipelines(const sim::RigPhysics& physics, std::uint64_t seed,
                        const std::string& dump_theta, bool verbose,
                        std::vector<Pipeline>* pipelines) {
  for (Pipeline& pl : *pipelines) {
    if (pl.recover_response) RecoverResponse(physics, seed, &pl);
    SweepRenderer sr(physics, seed);
    const auto brackets = sr.Run(CalibrationPoses(), CalibrationTMs(), pl.features);
    pl.model = Fit(Samples(brackets), pl.features, pl.fit);
    if (pl.blob_fit) RefitWithBlobFit(physics, seed, &pl);
    if (!dump_theta.empty() && pl.name == "default") DumpTheta(dump_theta, pl, brackets);
    PrintCalibration(pl, verbose);
  }
}

}  // namespace irdist::accuracy
