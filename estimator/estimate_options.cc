// EstimateOptions (estimate.h): their checks, the paper's set and their names.
#include <sstream>
#include <string>

#include "estimator/estimate.h"

namespace irdist {

bool EstimateOptions::IsValid(std::string* why) const {
  auto fail = [why](const char* text) {
    if (why) *why = text;
    return false;
  };
  if (max_iterations < 1) return fail("max_iterations must be >= 1");
  if (!(step_tolerance > 0.0)) return fail("step_tolerance must be > 0");
  if (!(range_margin >= 0.0)) return fail("range_margin must be >= 0");
  if (!(theta_prior_sd_deg > 0.0)) return fail("theta_prior_sd_deg must be > 0");
  if (!(radiometric_weight > 0.0)) return fail("radiometric_weight must be > 0");
  if (!(geometric_weight >= 0.0)) return fail("geometric_weight must be >= 0");
  if (!(radiometric_huber >= 0.0)) return fail("radiometric_huber must be >= 0 (0 = off)");
  return true;
}

EstimateOptions PaperEstimateOptions() {
  EstimateOptions options;
  options.method = EstimateMethod::kAlgorithm1;
  options.theta_source = ThetaSource::kFeatures;
  options.tie_breaker = RootTieBreaker::kResidualVote;
  options.theta_correction = false;
  return options;
}

const char* ToString(EstimateMethod method) {
  return method == EstimateMethod::kAlgorithm1 ? "algorithm1" : "fused";
}
const char* ToString(ThetaSource source) {
  switch (source) {
    case ThetaSource::kFeatures:
      return "features";
    case ThetaSource::kCalibratedBlur:
      return "calibrated_blur";
    case ThetaSource::kBracketMoments:
      return "bracket_moments";
  }
  return "unknown";
}
const char* ToString(RootTieBreaker tie_breaker) {
  return tie_breaker == RootTieBreaker::kResidualVote ? "residual_vote" : "geometric";
}

}  // namespace irdist
