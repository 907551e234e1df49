#pragma once
// Algorithm 1 of the paper: distance d and orientation theta of the IRED from one bracket
// (reference frame + N measurement frames), independent of the radiant intensity I0, with the
// calibrated I0-free models (Eq. 17, 18). And the geometric baseline's estimate.

#include <string>
#include <vector>

#include "estimator/features.h"
#include "estimator/fit.h"

namespace irdist {

struct EstimateOptions {
  int max_iterations = 50;        // LM iterations of Eq. 26
  double step_tolerance = 1e-12;  // stop when the step in (ln d, theta rad) is below this
  // Roots of Eq. 25 are "in range" within [d_min / (1 + m), d_max * (1 + m)].
  double range_margin = 0.10;
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

struct GeometricEstimate {
  bool valid = false;  // a blob with a second moment above the calibrated blur
  double d_mm = 0.0;
  bool outside_calibrated_range = false;
  std::string BriefReport() const;
};

// The geometric baseline (fit.h, GeometricModel) on one frame's features.
GeometricEstimate EstimateGeometric(const CalibrationModel& model, const Features& features);

}  // namespace irdist
