#pragma once
// The fit judges itself: the calibrated model's residuals on its own calibration
// frames against their noise. Per pose (one bracket: slide, pan, tilt, current), each feature the
// model predicts is a channel: the blob's major and minor moment variances (GeometricModel: disc
// plus calibrated blur), and the differences dE_rel and dSigma of the I0-free models. A channel's
// pose residual is the mean relative residual of the pose's measurement frames; its noise is the
// frames' own scatter inside the bracket (the pose is the same, only the exposure changes), pooled
// over the poses at the same distance: a noise the model's fit does not set. Then
//   chi2(pose) = sum over channels  rbar^2 / (s^2 k / n + floor^2)
// with n the pose's frames, k = 1 for the sizes and n + 1 for the differences (they share the
// reference frame, whose noise is at most a measurement frame's), and a stated model-error floor
// per channel. The fit fails its own test when the reduced chi-square lies beyond the chi-square
// quantile for its degrees of freedom (pose-channels minus fitted parameters) at the tail
// probability, or when one pose's chi-square lies beyond its quantile at the tail probability
// divided by the number of poses. docs/estimator.md "The fit's fitness".

#include <string>
#include <vector>

#include "estimator/fitness_figure.h"

namespace irdist {

struct CalibrationModel;
struct CalibrationSample;

struct FitnessOptions {
  // The tail probability of a good calibration failing (the chi-square quantile's complement).
  double tail_probability = 1e-3;
  // Model-error floors (relative sd of a pose's mean residual), added to the noise in quadrature:
  // what the models' families leave on a good calibration of every shipped virtual rig, whose
  // worst poses miss by 0.2-0.5% (docs/estimator.md gives the figures they were set from).
  double size_floor = 0.001;        // major and minor moment variances
  double difference_floor = 0.001;  // dE_rel and dSigma of the I0-free models
  int worst_poses = 5;               // how many are named
  bool IsValid(std::string* why) const;
};

// The figure of `model` over `samples` (each sample's `pose` indexes `poses`; samples without a
// pose are left out). Not assessed when fewer than 2 poses have 2 usable measurement frames.
CalibrationFitness AssessFitness(const CalibrationModel& model,
                                 const std::vector<CalibrationSample>& samples,
                                 const std::vector<FitnessPose>& poses,
                                 const FitnessOptions& options = {});

}  // namespace irdist
