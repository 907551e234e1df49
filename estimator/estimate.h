#pragma once
// Algorithm 1 of the paper: distance d and orientation theta of the IRED from one bracket
// (reference frame + N measurement frames), independent of the radiant intensity I0, with the
// calibrated I0-free models (Eq. 17, 18). And the geometric baseline's estimate.

#include <string>
#include <vector>

#include "estimator/features.h"
#include "estimator/fit.h"
#include "estimator/model_poles.h"

namespace irdist {

// How a bracket's distance is solved (docs/estimator.md: measured on the virtual rig).
enum class EstimateMethod {
  kAlgorithm1,  // the paper: Eq. 25 root, then Eq. 26 by LM (E and Sigma equations)
  // Default. Eq. 26's equations plus one geometric equation per measurement frame (the blob's
  // second-moment size, fit.h GeometricModel), each residual divided by its calibration fit's
  // mean relative error (the paper's suggested weighting), theta from the prior below.
  kFused,
};
// Where theta0 (the start, and for kFused the prior) comes from.
enum class ThetaSource {
  kFeatures,        // Features::theta0_deg (the ellipse chosen by FeatureOptions)
  kCalibratedBlur,  // default: the moment ellipse with the calibrated blur variance removed
  // The moment matrices of every frame of the bracket (the reference and the measurements)
  // averaged with weights proportional to their signal (the variance of a second moment falls
  // as 1 / signal in the shot-noise regime), then the calibrated blur removed. EstimatePair
  // and the per-exposure estimates use their pair (reference + measurement).
  kBracketMoments,
};
// How the root of Eq. 25 is chosen among several in range.
enum class RootTieBreaker {
  kResidualVote,  // smallest residual in the voting equations (the paper's criterion)
  kGeometric,     // default: the root nearest the geometric estimate
};
const char* ToString(EstimateMethod method);
const char* ToString(ThetaSource source);
const char* ToString(RootTieBreaker tie_breaker);

struct EstimateOptions {
  EstimateMethod method = EstimateMethod::kFused;
  ThetaSource theta_source = ThetaSource::kCalibratedBlur;
  RootTieBreaker tie_breaker = RootTieBreaker::kGeometric;
  // kCalibratedBlur / kBracketMoments: map the moment ellipse to theta with the model's calibrated
  // theta correction (fit.h ThetaCorrection) when the model has one; otherwise (false, the
  // default) theta0 = acos of the blur-corrected axis ratio. Not the default: on the virtual rig
  // the ellipse bias is not smooth in d at the scale of Table 3's 500 mm grid and the correction
  // made theta worse (docs/estimator.md).
  bool theta_correction = false;
  // kFused with an informative E equation (theta solved): sd of the theta prior, deg. With a
  // degenerate E (fixed window) theta is the prior itself: the Sigma equation barely sees it.
  double theta_prior_sd_deg = 0.5;
  // kFused: multipliers on the fit-derived weights of the radiometric (E, Sigma) equations and
  // of the geometric ones (1 = the calibration fits' mean relative errors as they are). 0.5
  // measured best on the virtual rig (docs/estimator.md): a dS fit error maps to less than the
  // same error in d, so the fit-error weight overrates the Sigma equation.
  double radiometric_weight = 0.5;
  double geometric_weight = 1.0;
  // kFused: the reference frame's size is one more geometric equation, weighted by its share of
  // the light against the measurement frames', sqrt(t_ref / mean t_n) x the geometric weight (a
  // size's noise falls as 1 / sqrt(signal)). false: the measurement frames' sizes only.
  bool reference_size = true;
  // kFused: Huber threshold on the weighted radiometric residuals (units: calibration mean fit
  // errors x radiometric_weight, so 3 = 6 fit errors); beyond it an equation counts linearly,
  // not quadratically. Where a calibration between sparse grid points misses a measurement by
  // far more than its fit error (14% against 0.08% on a 3-distance grid), the Sigma equation
  // would otherwise outvote the geometric ones (-2.4% in d there, -0.4% with it). On the Table 3
  // validations it never engages (figures identical). 0 = plain least squares.
  double radiometric_huber = 3.0;
  int max_iterations = 50;        // LM iterations of Eq. 26
  double step_tolerance = 1e-12;  // stop when the step in (ln d, theta rad) is below this
  // Roots of Eq. 25 are "in range" within [d_min / (1 + m), d_max * (1 + m)].
  double range_margin = kDefaultRangeMargin;
  bool IsValid(std::string* why) const;
};

enum class RootSource {
  kCubic,        // a real positive root of Eq. 25 (c - a) inside the calibrated range
  kSigmaOnly,    // E equation degenerate: a root of the Sigma equation alone (Eq. 23)
  kSingleModel,  // no in-range root of Eq. 25: a root of one equation alone
  kFallback,     // no usable root: the middle of the calibrated range
};
const char* ToString(RootSource source);

struct DistanceEstimate {
  double d_mm = 0.0;
  double theta_deg = 0.0;
  double d0_mm = 0.0;       // start: the chosen root
  double theta0_deg = 0.0;  // start: the ellipse
  RootSource root_source = RootSource::kFallback;
  int root_index = -1;  // index of the chosen root among the real roots, ascending D
  int num_real_roots = 0;
  int num_roots_in_range = 0;
  double residual_e = 0.0;  // rms relative residual of the E equation(s) at the solution
  double residual_sigma = 0.0;
  int iterations = 0;
  // Singular-value ratio of the Jacobian of the residuals with respect to (ln d, theta in rad) at
  // the solution (2x2 for one exposure; 2N x 2 jointly). 1-D (theta fixed) reports 1.
  double condition_number = -1.0;
  bool theta_solved = false;  // false when the E equation is degenerate: theta stays theta0
  // Standard errors from the solver's covariance, (J^T J)^-1 of the residuals weighted by the
  // calibration fits' mean relative errors (kFused); -1 when not computed (kAlgorithm1).
  double d_std_mm = -1.0;
  double theta_std_deg = -1.0;
  double d_geometric_mm = 0.0;  // mean geometric estimate of the measurement frames (0: none)
  bool converged = false;
  bool outside_calibrated_range = false;
  std::string BriefReport() const;
};

struct BracketEstimate {
  std::vector<DistanceEstimate> per_exposure;  // one per measurement frame, in input order
  DistanceEstimate joint;                      // Eq. 26 over all t_n of the bracket
  std::string BriefReport() const;
};

constexpr int kMaxBracketExposures = 16;

// One reference frame and one measurement frame: no heap allocation.
DistanceEstimate EstimatePair(const CalibrationModel& model, const Features& reference,
                              double t_ref_ms, const Features& measurement, double t_ms,
                              const EstimateOptions& options);

// Algorithm 1 for a bracket: per exposure, then jointly. measurements.size() == t_ms.size(), at
// most kMaxBracketExposures. Throws CheckError if the model lacks kFreeE or kFreeSigma.
BracketEstimate EstimateBracket(const CalibrationModel& model, const Features& reference,
                                double t_ref_ms, const std::vector<Features>& measurements,
                                const std::vector<double>& t_ms, const EstimateOptions& options);

// The paper's pipeline as specified (Algorithm 1 per t_n, theta0 from the ellipse, root of
// Eq. 25 by residual vote), for reporting beside the defaults.
EstimateOptions PaperEstimateOptions();

}  // namespace irdist
