#pragma once
// Calibration: fits the paper's models (estimator/models.h) to samples of known pose by
// Levenberg-Marquardt (Ceres) on relative residuals, from a linear (SVD) start per sigma on a scan,
// with the scale gauge of the ratio models fixed by holding one coefficient at 1. Also fits the
// purely geometric baseline (distance from the blob's second-moment size).

#include <string>
#include <vector>

#include "estimator/features.h"
#include "estimator/models.h"

namespace irdist {

// One difference of one pose: the reference frame and one measurement frame.
struct CalibrationSample {
  Features reference;
  Features measurement;
  double t_ref_ms = 0.0;
  double t_ms = 0.0;
  double bias_ma = 0.0;
  double d_mm = 0.0;
  double theta_deg = 0.0;
};

struct FitOptions {
  // Models to fit; Algorithm 1 needs kFreeE and kFreeSigma.
  std::vector<ModelKind> models = {
      ModelKind::kDirectE, ModelKind::kDirectF,   ModelKind::kDirectSigma, ModelKind::kDiffE,
      ModelKind::kDiffF,   ModelKind::kDiffSigma, ModelKind::kFreeE,       ModelKind::kFreeSigma};
  // Form of the I0-free models (kReduced drops the dt^2 terms; kFull is the paper's Eq. 17-18).
  ModelForm free_form = ModelForm::kReduced;
  // Scan of the Gaussian dispersion sigma (deg) for the linear starts, geometric spacing.
  double sigma_min_deg = 5.0;
  double sigma_max_deg = 200.0;
  int sigma_scan_steps = 16;
  // The best `multi_starts` linear starts of the scan are each refined by LM; the best wins.
  int multi_starts = 3;
  int max_iterations = 1000;          // per LM run
  double function_tolerance = 1e-16;  // Ceres' relative cost change
  double gradient_tolerance = 1e-20;
  double parameter_tolerance = 1e-14;
  // An E equation whose targets are proportional to F's within this relative deviation (fixed
  // window + identity response: E_rel = F / (A max)) is marked degenerate and gets no vote.
  double degenerate_tolerance = 1e-6;
  // Skip samples whose features are flagged (no blob, saturated, border, clipped).
  bool skip_flagged_samples = true;
  bool IsValid(std::string* why) const;
};

struct FitSummary {
  enum class Termination { kConverged, kNoConvergence, kFailed };
  Termination termination = Termination::kFailed;
  std::string message = "Fit() was not called.";
  double mean_relative_error = -1.0;  // fraction: mean |model/measured - 1|
  double max_relative_error = -1.0;   // fraction
  // Singular-value ratio s_max/s_min of the Jacobian of the relative residuals with respect to the
  // free parameters (scaled coefficients except the gauge and inactive ones, and sigma), at the
  // solution. Not J^T J's ratio (which is this squared).
  double condition_number = -1.0;
  int samples = 0;
  int iterations = 0;             // LM iterations of the winning start
  int gauge_index = -1;           // coefficient held at 1 (ratio models), -1 if none
  std::vector<double> residuals;  // relative residual per observation, in input order
  std::string BriefReport() const;
};

const char* ToString(FitSummary::Termination termination);

struct FittedModel {
  ModelKind kind = ModelKind::kFreeSigma;
  ModelForm form = ModelForm::kFull;
  std::vector<double> coefficients;  // GetModelSpec(kind).num_coefficients(), inactive ones 0
  double sigma_deg = 0.0;            // Gaussian dispersion of rho
  bool degenerate = false;  // carries no information (see FitOptions::degenerate_tolerance)
  FitSummary summary;
  double Predict(const ModelScaling& scaling, const ModelInputs& inputs) const {
    return PredictModel(kind, coefficients, sigma_deg, scaling, inputs);
  }
};

// The calibrated domain; estimates outside it are flagged.
struct CalibratedRanges {
  double d_min_mm = 0.0, d_max_mm = 0.0;
  double theta_min_deg = 0.0, theta_max_deg = 0.0;
  double t_min_ms = 0.0, t_max_ms = 0.0;  // measurement exposures
  double t_ref_min_ms = 0.0, t_ref_max_ms = 0.0;
  double bias_min_ma = 0.0, bias_max_ma = 0.0;
};

// Geometric baseline: the blob's major-axis second moment (px^2) is alpha * D + beta, D = (1000 mm
// / d)^2: the image of the disc scales as 1/d, its variance as 1/d^2, and the blur adds a constant.
// Inverted: d = 1000 / sqrt((var - beta) / alpha). Fitted by linear least squares on relative
// residuals, from the measurement frames (exposure does not change background-subtracted moments).
struct GeometricModel {
  double alpha_px2 = 0.0;
  double beta_px2 = 0.0;
  FitSummary summary;
  bool fitted() const { return alpha_px2 > 0.0; }
};

// Everything Algorithm 1 needs, and everything the model file holds.
struct CalibrationModel {
  FeatureOptions features;  // ROI policy and its parameters, identical in measurement
  ModelScaling scaling;
  CalibratedRanges ranges;
  std::vector<FittedModel> models;
  GeometricModel geometric;
  const FittedModel* Find(ModelKind kind) const;  // nullptr if not fitted
  std::string BriefReport() const;
};

// The paper's calibration as specified: the full Eq. 17-18 forms (dt^2 terms kept).
FitOptions PaperFitOptions();

// Fits one model to the samples (scaling given). Throws CheckError on invalid options or on fewer
// samples than coefficients.
FittedModel FitModel(ModelKind kind, ModelForm form, const std::vector<CalibrationSample>& samples,
                     const ModelScaling& scaling, const FitOptions& options);

// Scalings that bring every model input near 1 for these samples.
ModelScaling ChooseScaling(const std::vector<CalibrationSample>& samples);

GeometricModel FitGeometric(const std::vector<CalibrationSample>& samples);

// Full calibration: scalings, ranges, every model of options.models and the geometric baseline.
// feature_options is recorded (it must be what computed the samples' features).
CalibrationModel Fit(const std::vector<CalibrationSample>& samples,
                     const FeatureOptions& feature_options, const FitOptions& options);

}  // namespace irdist
