#pragma once
// The accuracy study's machinery (bench/accuracy/accuracy_study.cc runs it): the sweep renderer
// with the IRED's thermal history, the pipelines (feature, fit and estimate options with the
// calibrated model), the estimates of every method per bracket, and the summary figures printed
// per experiment. In namespace irdist::accuracy: the study's Pose, Row and Print are its own, not
// station/pose.h's or the app's.
#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "estimator/blob_fit.h"
#include "estimator/estimate.h"
#include "estimator/features.h"
#include "estimator/fit.h"
#include "estimator/response.h"
#include "sim/renderer.h"
#include "sim/rig_physics.h"

namespace irdist::accuracy {

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
                           const CalibrationModel* refine = nullptr);
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

struct Figures {
  int n = 0, failed = 0;
  double med = 0, p95 = 0, max = 0;  // relative distance error, %
  double th_med = 0, th_max = 0;     // |theta error| for theta >= 15, deg
  double shift = 0;                  // current shift, %
  double disp = 0;                   // largest sd over repetitions, mm
  Pose worst_theta{0, 0, 0, 0};      // pose of the largest theta error (theta >= 15)
};

Figures Summarise(const std::vector<Row>& rows, bool theta_reported);
void Print(const char* experiment, const char* method, const Figures& f, bool theta_reported);

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
                    const char* experiment);

// Every bracket estimated by the pipeline (its rows in m->rows[pl.name], its health counts); with
// `with_baselines`, also by the I0-dependent model at `nominal_ma` and the geometric baseline.
void Estimate(const Pipeline& pl, const std::vector<Bracket>& brackets, Methods* m,
              bool with_baselines, double nominal_ma);

struct Experiment {
  const char* name;
  std::vector<Pose> poses;
  std::vector<double> t_ms;
};

// Validation on a rig whose blur changed after calibration: the default pipeline's health flags
// and distance errors (the model stays the unchanged rig's).
void RunBlurChange(const sim::RigPhysics& physics, std::uint64_t seed, double change,
                   const std::vector<Pipeline>& pipelines, const std::vector<Experiment>& experiments);

// a, a + step, ... up to b inclusive.
std::vector<double> Range(double a, double b, double step);

// Which pipelines the study runs (its flags).
struct PipelineChoice {
  std::vector<std::string> radiometric_weights;  // --radiometric-weight W, as given
  std::vector<std::string> theta_degrees;        // --theta-degree N, as given
  bool only_default = false;    // the default, fixed_blur and blob_fit pipelines only
  bool model_fit = false;       // pipeline model_fit: theta0 from EllipseMethod::kModelFit
  bool theta_variants = false;  // pipelines theta_bracket, threshold and blob_fit_bracket
};

// The pipelines in the study's order: paper, default, alg1_joint, one fused_w<W> per radiometric
// weight, theta_cal, one theta_cal_deg<N> per degree, response, fixed_blur, blob_fit (with
// only_default, just the last three of default, fixed_blur and blob_fit), then the theta variants.
std::vector<Pipeline> BuildPipelines(const PipelineChoice& choice);

// Table 3's calibration fitted for every pipeline and printed; with `verbose` the whole model too.
// `dump_theta`, when not empty: the CSV of the default pipeline's calibration frames (true pose,
// moment variances, theta0 without and with the calibrated correction).
void CalibratePipelines(const sim::RigPhysics& physics, std::uint64_t seed,
                        const std::string& dump_theta, bool verbose,
                        std::vector<Pipeline>* pipelines);

// Per angle of Fig. 14: sd of d and of theta over the repetitions, and the mean error, for the
// methods that estimate from the whole bracket.
void PrintDispersion(const Methods& m);

}  // namespace irdist::accuracy
