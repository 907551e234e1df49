#pragma once
// theta's start for Algorithm 1 (estimator-internal, estimate.cc): from the blob's shape, the
// signal-weighted moment matrices of a bracket's frames or one frame's, with the calibrated blur
// removed (EstimateOptions::theta_source and theta_correction).

#include <string>

#include "estimator/features.h"
#include "estimator/fit.h"

namespace irdist {

struct ThetaStartOptions {
  bool from_features = false;   // ThetaSource::kFeatures: the frame's own theta0
  bool bracket_moments = true;  // ThetaSource::kBracketMoments: the frames' moments together
  bool correction = true;       // through the model's calibrated theta correction when it has one
  // The first problem in *why (empty when valid): one source, never both.
  bool IsValid(std::string* why) const {
    const std::string reason =
        from_features && bracket_moments ? "from_features and bracket_moments both set" : "";
    if (why != nullptr) *why = reason;
    return reason.empty();
  }
};

// theta0 (deg) from the signal-weighted mean of the frames' moment matrices (bracket_moments),
// the calibrated blur removed: acos of the axis ratio, or the calibrated correction; else (or when
// no frame has moments) that of `fallback` alone (its fitted disc's own blur where the blob fit
// set it, else the geometric model's b(u)); its features' theta0 when from_features or the model
// has no geometric fit.
double Theta0Combined(const CalibrationModel& model, const Features* const* frames, int count,
                      const Features& fallback, const ThetaStartOptions& options);

}  // namespace irdist
