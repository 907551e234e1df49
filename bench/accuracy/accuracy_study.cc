// Accuracy study on the virtual rig without GigE or serial: frames rendered directly with
// sim::Renderer (sensor noise, per-frame seeds, the IRED's self-heating along the sweep), the
// Table 3 calibration fitted, and the validation grids of Fig. 10, 13 and 14 estimated by every
// method: the paper's pipeline (Algorithm 1 per t_n, full Eq. 17-18, fixed window), the default
// pipeline (estimator defaults), the I0-dependent direct model at the nominal current and the
// geometric baseline; pipeline `response` is the default estimator on features linearised by the
// camera response recovered from the calibration's brackets (estimator/response.h). Prints each
// method's figures per experiment. Usage:
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
#include <random>
#include <string>
#include <vector>

#include "app/processing/crb.h"
#include "bench/accuracy/accuracy_pipeline.h"
#include "estimator/features.h"
#include "sim/renderer.h"
#include "sim/rig_physics.h"

namespace irdist::accuracy {
namespace {

// The study's flags (--help lists them).
struct StudyArgs {
  std::string rig = std::string(IRDIST_SOURCE_DIR) + "/recipes/rigs/virtual.yaml";
  std::uint64_t seed = 7;
  bool quick = false;
  bool verbose = false;
  bool crb_only = false;
  bool theta_probe = false;
  double nonlinearity = -1.0;  // --nonlinearity A: the rig's sensor nonlinearity replaced by A
  std::vector<double> blur_changes;  // --blur-change X: validate with the blur changed by X
  std::string dump_theta;  // CSV of the calibration frames' moments and theta0 (default pipeline)
  PipelineChoice pipelines;
};

void PrintHelp() {
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
}

// The value after every `flag` on the command line (each value skipped, not read as a flag).
std::vector<std::string> FlagValues(int argc, char** argv, const char* flag) {
  std::vector<std::string> values;
  for (int i = 1; i < argc; ++i)
    if (!std::strcmp(argv[i], flag) && i + 1 < argc) values.push_back(argv[++i]);
  return values;
}

// Fills `args` from the command line; false after --help's text is printed (nothing to run).
bool ParseStudyArgs(int argc, char** argv, StudyArgs* args) {
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--rig") && i + 1 < argc)
      args->rig = argv[++i];
    else if (!std::strcmp(argv[i], "--seed") && i + 1 < argc)
      args->seed = std::stoull(argv[++i]);
    else if (!std::strcmp(argv[i], "--nonlinearity") && i + 1 < argc)
      args->nonlinearity = std::stod(argv[++i]);
    else if (!std::strcmp(argv[i], "--quick"))
      args->quick = true;
    else if (!std::strcmp(argv[i], "--theta-variants"))
      args->pipelines.theta_variants = true;
    else if (!std::strcmp(argv[i], "--model-fit"))
      args->pipelines.model_fit = true;
    else if (!std::strcmp(argv[i], "--theta-probe"))
      args->theta_probe = true;
    else if (!std::strcmp(argv[i], "--blur-change") && i + 1 < argc)
      args->blur_changes.push_back(std::stod(argv[++i]));
    else if (!std::strcmp(argv[i], "--only-default"))
      args->pipelines.only_default = true;
    else if (!std::strcmp(argv[i], "--crb-only"))
      args->crb_only = true;
    else if (!std::strcmp(argv[i], "--help")) {
      PrintHelp();
      return false;
    } else if (!std::strcmp(argv[i], "--verbose"))
      args->verbose = true;
    else if (!std::strcmp(argv[i], "--dump-theta") && i + 1 < argc)
      args->dump_theta = argv[++i];
    else if (!std::strcmp(argv[i], "--radiometric-weight") ||
             !std::strcmp(argv[i], "--theta-degree"))
      ++i;
  }
  args->pipelines.radiometric_weights = FlagValues(argc, argv, "--radiometric-weight");
  args->pipelines.theta_degrees = FlagValues(argc, argv, "--theta-degree");
  return true;
}

// Exposure linearity of the renderer and sensor (the acquisition report of 4.05x at 36 ms):
// frame signal above the black level, 36 ms vs 8 ms, at a fixed junction rise and across a
// cold start (the current switched on just before the 8 ms frame).
void PrintExposureLinearity(const sim::RigPhysics& physics) {
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
void PrintCramerRao(const sim::RigPhysics& physics) {
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

// theta0 from a second-moment matrix (xx, yy, xy) with the blur variance `beta` removed.
double ThetaFromMoments(double xx, double yy, double xy, double beta) {
  const double tr = xx + yy;
  const double root = std::sqrt(std::max(0.0, 0.25 * (xx - yy) * (xx - yy) + xy * xy));
  const double major = 0.5 * tr + root - beta, minor = 0.5 * tr - root - beta;
  if (!(major > 0)) return 0;
  return std::acos(std::clamp(std::sqrt(std::max(0.0, minor) / major), 0.0, 1.0)) * 180 / M_PI;
}

// The second-moment matrix (xx, yy, xy) of a frame's moment ellipse.
void MomentMatrix(const Features& x, double* xx, double* yy, double* xy) {
  const double a = x.ellipse_moments.angle_deg * M_PI / 180;
  const double l1 = x.moment_major_var_px2, l2 = x.moment_minor_var_px2;
  *xx = l1 * std::cos(a) * std::cos(a) + l2 * std::sin(a) * std::sin(a);
  *yy = l1 * std::sin(a) * std::sin(a) + l2 * std::cos(a) * std::cos(a);
  *xy = (l1 - l2) * std::sin(a) * std::cos(a);
}

// What every pose of the theta probe shares: the renderer and its frame, the blur variance the
// moments lose (lens PSF and pixel), and the steady junction rise at 500 mA.
struct ThetaProbeRig {
  ThetaProbeRig(const sim::RigPhysics& physics, std::uint64_t seed_in)
      : renderer(physics),
        origin(physics.sensor.width_px / 2 - kSide / 2, physics.sensor.height_px / 2 - kSide / 2),
        frame(kSide, kSide, CV_16UC1),
        beta(physics.optics.psf_sigma_px * physics.optics.psf_sigma_px + 1.0 / 12),
        steady(physics.emitter.thermal_resistance_k_per_w * 0.5 *
               physics.emitter.forward_voltage_v),
        seed(seed_in) {}

  // Repetition `rep`'s frame k (0: the 8 ms reference, 1: the 35 ms measurement), its features.
  Features Frame(double d, double th, int rep, int k, const FeatureOptions& fo) {
    sim::FrameConditions c = sim::StaticConditions(d, th, 0, 500, (k ? 35.0 : kTRefMs) * 1e-3);
    c.junction_rise_k = steady;
    renderer.Render(c, seed * 1000003ull + rep * 2 + k, sim::PixelFormat::kMono12, origin, frame);
    return ComputeFeatures(frame, 12, fo);
  }

  static constexpr int kSide = 192;
  sim::Renderer renderer;
  cv::Point origin;
  cv::Mat frame;
  double beta, steady;
  std::uint64_t seed;
};

// theta0 over 60 repetitions per moment variant (`fractions`: > 0 threshold moments at that
// fraction, < 0 aperture moments with that margin in px), three per variant: from the 35 ms
// frame, from both frames' moments weighted by signal, from the 8 ms frame.
std::vector<std::vector<double>> MomentThetas(ThetaProbeRig& rig, double d, double th,
                                              const std::vector<double>& fractions) {
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
      for (int k = 0; k < 2; ++k) f[k] = rig.Frame(d, th, rep, k, fo);
      double m[2][3];
      for (int k = 0; k < 2; ++k) MomentMatrix(f[k], &m[k][0], &m[k][1], &m[k][2]);
      meas[fi * 3].push_back(ThetaFromMoments(m[1][0], m[1][1], m[1][2], rig.beta));
      const double w0 = f[0].f00 - f[0].background * f[0].roi_area_px;
      const double w1 = f[1].f00 - f[1].background * f[1].roi_area_px;
      double c[3];
      for (int j = 0; j < 3; ++j) c[j] = (w0 * m[0][j] + w1 * m[1][j]) / (w0 + w1);
      meas[fi * 3 + 1].push_back(ThetaFromMoments(c[0], c[1], c[2], rig.beta));
      meas[fi * 3 + 2].push_back(ThetaFromMoments(m[0][0], m[0][1], m[0][2], rig.beta));
    }
  }
  return meas;
}

// Bias and sd of theta0 per moment variant at one pose.
void ProbeMomentVariants(ThetaProbeRig& rig, double d, double th) {
  // > 0: threshold moments at that fraction; < 0: aperture moments with that margin (px).
  std::vector<double> fractions = {0.02, -2.0, -3.0, -5.0};
  const std::vector<std::vector<double>> meas = MomentThetas(rig, d, th, fractions);
  for (size_t v = 0; v < meas.size(); ++v) {
    double mean = 0, sd = 0;
    for (double x : meas[v]) mean += x / meas[v].size();
    for (double x : meas[v]) sd += (x - mean) * (x - mean) / (meas[v].size() - 1);
    std::printf("  %s %.2f %-10s bias %+.3f sd %.3f\n", fractions[v / 3] > 0 ? "thr" : "ap.margin",
                std::abs(fractions[v / 3]),
                v % 3 == 0 ? "35ms" : v % 3 == 1 ? "combined" : "8ms", mean - th,
                std::sqrt(sd));
  }
}

// EllipseMethod::kModelFit: theta0 of the fitted blurred disc, per frame.
void ProbeModelFit(ThetaProbeRig& rig, double d, double th) {
  std::vector<double> fit_theta[2], fit_blur;
  FeatureOptions fo;
  fo.ellipse_method = EllipseMethod::kModelFit;
  for (int rep = 0; rep < 60; ++rep) {
    for (int k = 0; k < 2; ++k) {
      const Features f = rig.Frame(d, th, rep, k, fo);
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

// Dispersion and bias of theta0 variants over repeated frames of static poses (8 ms reference,
// 35 ms measurement), beside the Cramer-Rao bound.
void ThetaProbe(const sim::RigPhysics& physics, std::uint64_t seed) {
  ThetaProbeRig rig(physics, seed);
  for (double d : {2100.0, 2900.0}) {
    for (double th : {15.0, 20.0, 30.0}) {
      const CrbResult crb = ComputeCrb(physics, {d, th, 500.0, rig.steady, {kTRefMs, 35.0}});
      std::printf("%g mm %g deg: CRB theta %.3f deg\n", d, th, crb.theta_sd_deg);
      ProbeMomentVariants(rig, d, th);
      ProbeModelFit(rig, d, th);
    }
  }
}

// Validation grids: Fig. 10 (distance, angle and current), Fig. 13 (random currents around
// 500 mA) and Fig. 14 (repetitions at 2.7 m; 20 per angle with --quick, else 100).
std::vector<Experiment> ValidationGrids(bool quick, std::uint64_t seed) {
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
  return experiments;
}

// One experiment's figures per method, its health flags and, for Fig. 14, the dispersion.
void PrintExperiment(const Experiment& ex, const Methods& m) {
  std::printf("%s (%zu brackets, t_n", ex.name, ex.poses.size());
  for (double t : ex.t_ms) std::printf(" %g", t);
  std::printf(" ms):\n");
  for (const auto& [name, rows] : m.rows) {
    if (name == "default" && !rows.empty()) {
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

// One validation grid estimated by every pipeline (the default's also by the baselines).
void Validate(const sim::RigPhysics& physics, std::uint64_t seed,
              const std::vector<Pipeline>& pipelines, const Experiment& ex) {
  Methods m;
  for (size_t p = 0; p < pipelines.size(); ++p) {
    SweepRenderer sr(physics, seed + 100);
    const Pipeline& pl = pipelines[p];
    const auto brackets =
        sr.Run(ex.poses, ex.t_ms, pl.features, nullptr, pl.blob_fit ? &pl.model : nullptr);
    Estimate(pipelines[p], brackets, &m, pipelines[p].name == "default", 500.0);
    if (pipelines[p].name == "default") PrintBlurCheck(pipelines[p].model, brackets, ex.name);
  }
  PrintExperiment(ex, m);
}

int Main(int argc, char** argv) {
  StudyArgs args;
  if (!ParseStudyArgs(argc, argv, &args)) return 0;
  sim::RigPhysics physics = sim::LoadRigPhysics(args.rig);
  if (args.nonlinearity >= 0.0) physics.sensor.nonlinearity = args.nonlinearity;
  std::printf("rig %s, seed %llu, sensor nonlinearity %g\n", args.rig.c_str(),
              static_cast<unsigned long long>(args.seed), physics.sensor.nonlinearity);
  const auto t0 = std::chrono::steady_clock::now();
  PrintExposureLinearity(physics);
  PrintCramerRao(physics);
  if (args.crb_only) return 0;
  if (args.theta_probe) {
    ThetaProbe(physics, args.seed);
    return 0;
  }
  std::vector<Pipeline> pipelines = BuildPipelines(args.pipelines);
  CalibratePipelines(physics, args.seed, args.dump_theta, args.verbose, &pipelines);
  const std::vector<Experiment> experiments = ValidationGrids(args.quick, args.seed);
  for (const Experiment& ex : experiments) Validate(physics, args.seed, pipelines, ex);
  for (double change : args.blur_changes)
    RunBlurChange(physics, args.seed, change, pipelines, experiments);
  std::printf("elapsed %.1f s\n",
              std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  return 0;
}

}  // namespace
}  // namespace irdist::accuracy

int main(int argc, char** argv) { return irdist::accuracy::Main(argc, argv); }
