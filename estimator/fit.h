#pragma once
// Calibration: fits the paper's models (estimator/models.h) to samples of known pose by
// Levenberg-Marquardt (Ceres) on relative residuals, from a linear (SVD) start per sigma on a scan,
// with the scale gauge of the ratio models fixed by holding one coefficient at 1. Also fits the
// purely geometric baseline (distance from the blob's second-moment size).

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "estimator/features.h"
#include "estimator/blur_model.h"
#include "estimator/fitness_figure.h"
#include "estimator/models.h"
#include "estimator/provenance.h"

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
  int pose = -1;  // index of its pose (bracket) for the fitness (fitness.h); -1 = none
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
  // Fit the calibrated theta correction (ThetaCorrection below) of total degree
  // theta_correction_degree (1..3) in (squared axis ratio, geometric distance).
  bool fit_theta_correction = true;
  int theta_correction_degree = 2;
  // The geometric model's blur: one variance for every distance (the older, simpler model), or
  // the thin lens's blur variance, a quadratic in 1/d (or a cubic where the sizes ask for it;
  // GeometricModel), fitted with the disc's scale from both axes of every calibration frame
  // (default).
  bool geometric_blur_varies_with_distance = true;
  bool IsValid(std::string* why) const;
};

struct FitSummary {
  // kConverged: the solver converged on a full-rank, well-conditioned Jacobian. kDegenerate: it
  // converged but the Jacobian is rank-deficient (null directions in `message`); its residuals
  // say nothing about the model. kIllConditioned: converged, full rank, condition number above
  // kIllConditionedLimit (estimator/fit_status.h).
  enum class Termination { kConverged, kNoConvergence, kFailed, kDegenerate, kIllConditioned };
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
  // mean_relative_error and max_relative_error from |residuals| (-1 when there are none).
  void SetErrorsFromResiduals();
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
  // Signal level: the blob's peak gray level (Features::peak, normalised) over the calibration's
  // frames, reference and measurement; 0, 0 = not recorded (a model file before it).
  double peak_min = 0.0, peak_max = 0.0;
  // Whether d_mm (standard error se_mm; <= 0 or NaN: none) lies outside [d_min, d_max] by more
  // than z standard errors (and at least 1e-6 of d_max: the solver's own precision); theta
  // likewise (at least 1e-4 deg).
  bool DistanceOutside(double d_mm, double se_mm, double z) const {
    return OutsideEdges(d_mm, se_mm, d_min_mm, d_max_mm, z, 1e-6 * d_max_mm);
  }
  bool ThetaOutside(double theta_deg, double se_deg, double z) const {
    return OutsideEdges(theta_deg, se_deg, theta_min_deg, theta_max_deg, z, 1e-4);
  }

 private:
  static bool OutsideEdges(double value, double se, double lo, double hi, double z,
                           double floor) {
    const double margin = std::max(floor, se > 0.0 ? z * se : 0.0);
    return value < lo - margin || value > hi + margin;
  }
};

// Geometric baseline: the blob's second moment along the disc's major axis (px^2) is
// alpha u^2 + b(u), u = 1000 mm / d (so u^2 = D): the image of the disc scales as 1/d, its variance
// as 1/d^2, and the blur adds b(u) = beta + blur_u1 u + blur_u2 u^2. A lens focused at s blurs an
// object at d by a circle of confusion proportional to |1/s - 1/d|: its variance is quadratic in u,
// so b(u) holds a Gaussian lens PSF, the pixel's area and the defocus exactly; a real lens's
// blob (a defocus disc's PSF, a halo) grows otherwise: from 4 calibrated distances on, b(u) takes
// a cubic term blur_u3 u^3 (0: none).
// blur_u1 = blur_u2 = 0 is the fixed blur (model files before format 3, or
// FitOptions::geometric_blur_varies_with_distance off). Inverted: the positive root u of blur_u3
// u^3 + (alpha + blur_u2) u^2 + blur_u1 u + beta - var = 0 where the law rises with u (nearest the
// quadratic's root when there are several). Fitted by linear least squares on relative residuals,
// from the measurement frames (exposure does not change background-subtracted moments); with the
// distance-dependent blur, the minor axis (alpha cos^2(theta) u^2 + b(u), theta known at
// calibration) separates the disc from the blur.
struct GeometricModel {
  double alpha_px2 = 0.0;
  double beta_px2 = 0.0;
  double blur_u1_px2 = 0.0;
  double blur_u2_px2 = 0.0;
  // The size law's cubic term in u (format 4, optional; 0 in files before it and where not
  // taken): fitted from 4 or more calibrated distances (docs/estimator.md "Geometric baseline").
  double blur_u3_px2 = 0.0;
  // Per-frame noise of the relative distance it implies, as a function of d:
  // sd(d) = noise_rel_at_1m * (d / 1000 mm)^noise_exponent, fitted to the calibration residuals'
  // rms at each calibrated distance (the apparent size's noise grows with d). 0 = not fitted
  // (model files before it): standard errors then stay in units of the mean fit error.
  double noise_rel_at_1m = 0.0;
  double noise_exponent = 0.0;
  // The size's tilt term (optional; empty in files before it and where the sizes show none): a
  // blob fit's major-axis variance departs from the law by T(theta), px^2, when the lens's PSF is
  // not the fit's (an astigmatic or defocus-disc lens: the tilted disc's more curved ends),
  // measured on the calibration's own poses as a function of the frame's own theta (the fitted
  // disc's axes) and piecewise linear between knots at the calibrated angles (fit_tilt.cc).
  std::vector<double> tilt_theta_deg;  // increasing
  std::vector<double> tilt_var_px2;    // T at each knot
  FitSummary summary;
  bool fitted() const { return alpha_px2 > 0.0; }
  // T(theta), px^2: 0 without a tilt term; the end knots' value beyond them.
  double TiltVarPx2(double theta_deg) const;
  // The frame's major-axis variance for the law: its blob fit's less T at the fitted disc's own
  // theta; the moments' (no blob fit: size_blur_var_px2 NaN) as they are.
  double FrameMajorVarPx2(const Features& f) const;
  bool BlurVariesWithDistance() const {
    return blur_u1_px2 != 0.0 || blur_u2_px2 != 0.0 || blur_u3_px2 != 0.0;
  }
  // Blur variance b(u) (px^2, per axis) at distance d_mm.
  double BlurVarPx2(double d_mm) const;
  // The major-axis variance the model expects at d_mm.
  double MajorVarPx2(double d_mm) const { return alpha_px2 * 1e6 / (d_mm * d_mm) + BlurVarPx2(d_mm); }
  // The distance (mm) whose expected major-axis variance is major_var_px2; NaN when none.
  double DistanceMm(double major_var_px2) const;
  // The standard error (mm) of DistanceMm for a major-axis variance with standard error se_px2,
  // through the model's slope: half the distances at var -+ se apart. NaN when either is none.
  double DistanceSeMm(double major_var_px2, double se_px2) const;
  // sd(d) above; 0 when the noise model is not fitted.
  double NoiseRel(double d_mm) const {
    return noise_rel_at_1m > 0.0 ? noise_rel_at_1m * std::pow(d_mm / 1000.0, noise_exponent)
                                 : 0.0;
  }
};

// Calibrated theta correction. The moment ellipse with the calibrated blur variance beta removed
// gives x = (minor - beta) / (major - beta), ideally cos^2(theta); threshold cuts through the
// blob's wings and the blur make it deviate by a pose-dependent amount (docs/estimator.md). At
// calibration, where theta and d are known, cos^2(theta) is fitted by linear least squares as a
// polynomial of total degree `degree` in x and z, z the geometric distance (GeometricModel)
// mapped to [-1, 1] over [d_min_mm, d_max_mm]. Monomials in graded order: degree 1: 1, x, z;
// degree 2 adds x^2, x z, z^2; degree 3 adds x^3, x^2 z, x z^2, z^3. Applying it clamps x and z to
// their calibrated ranges (no extrapolation) and cos^2 to [0, 1].
struct ThetaCorrection {
  int degree = 0;
  std::vector<double> coefficients;  // empty: no correction (older model files)
  double ratio_sq_min = 0.0, ratio_sq_max = 1.0;  // calibrated range of x
  double d_min_mm = 0.0, d_max_mm = 0.0;          // calibrated range of the geometric distance
  // Residuals: corrected theta minus true theta of every calibration frame, in DEGREES (the
  // "relative error" fields hold degrees here).
  FitSummary summary;
  bool fitted() const { return !coefficients.empty(); }
  // Number of monomials of a total degree (1: 3, 2: 6, 3: 10).
  static int NumTerms(int degree) { return (degree + 1) * (degree + 2) / 2; }
  // theta (deg) from the moment variances of one frame (or a combined moment matrix), with the
  // geometric model's blur variance and scale. NaN when the blob is not larger than the blur.
  double ThetaDeg(double major_var_px2, double minor_var_px2, const GeometricModel& g) const;
};

// Everything Algorithm 1 needs, and everything the model file holds.
struct CalibrationModel {
  FeatureOptions features;  // ROI policy and its parameters, identical in measurement
  ModelScaling scaling;
  CalibratedRanges ranges;
  std::vector<FittedModel> models;
  GeometricModel geometric;
  ThetaCorrection theta_correction;  // not fitted: theta from the blur-corrected ratio alone
  ModelProvenance provenance;        // filled by the app from the recording (estimator/provenance.h)
  BlurCalibration blur_calibration;  // blur_model.h; not fitted in model files before format 4
  CalibrationFitness fitness;  // fitness_figure.h (fitness.h computes it), set by the app; optional
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

// blur_varies_with_distance: GeometricModel's b(u) quadratic in u (else the constant beta).
GeometricModel FitGeometric(const std::vector<CalibrationSample>& samples,
                            bool blur_varies_with_distance = false);

// Fits the theta correction on the measurement frames of the usable samples (degree 1..3). Not
// fitted (empty coefficients, summary message says why) without a fitted geometric model or with
// fewer than 2x the number of terms of usable frames.
ThetaCorrection FitThetaCorrection(const std::vector<CalibrationSample>& samples,
                                   const GeometricModel& geometric, int degree);

// Full calibration: scalings, ranges, every model of options.models and the geometric baseline.
// feature_options is recorded (it must be what computed the samples' features).
CalibrationModel Fit(const std::vector<CalibrationSample>& samples,
                     const FeatureOptions& feature_options, const FitOptions& options);

}  // namespace irdist
