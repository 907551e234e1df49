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

namespace irdist {

struct CalibrationModel;
struct CalibrationSample;

// Where a calibration pose was: the station's axes and the IRED's current set.
struct FitnessPose {
  double slide_mm = 0.0;
  double pan_deg = 0.0;
  double tilt_deg = 0.0;
  double bias_ma = 0.0;
};

// One pose's figure.
struct PoseFitness {
  FitnessPose pose;
  double chi2 = 0.0;
  int channels = 0;  // its degrees of freedom
  // The pose's own frame-to-frame scatter over its distance's pooled scatter (1 typical; far
  // above: the frames of the bracket disagree among themselves, the IRED moved during it).
  double scatter_ratio = 0.0;
  std::string worst_channel;       // the channel contributing most: "size", "minor", "dE", "dSigma"
  double worst_residual_percent = 0.0;  // that channel's mean relative residual, percent
};

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

// The model's figure over its calibration (model.yaml key `fitness`, optional).
struct CalibrationFitness {
  bool assessed = false;  // false: not computed (older models; too few poses with 2 frames)
  int poses = 0;
  int dof = 0;             // pose-channels minus fitted parameters
  double chi2 = 0.0;
  double reduced_chi2 = 0.0;
  double limit = 0.0;      // the reduced chi-square's limit
  double pose_limit = 0.0; // one pose's chi-square limit (at its own channels, the most common)
  double tail_probability = 0.0;
  double size_floor = 0.0, difference_floor = 0.0;
  int poses_over = 0;      // poses beyond pose_limit
  bool passed = true;
  std::string cause;       // the probable cause when it did not pass ("" when it did)
  std::vector<PoseFitness> worst;  // the worst poses, worst first
  std::string BriefReport() const;
};

// The figure of `model` over `samples` (each sample's `pose` indexes `poses`; samples without a
// pose are left out). Not assessed when fewer than 2 poses have 2 usable measurement frames.
CalibrationFitness AssessFitness(const CalibrationModel& model,
                                 const std::vector<CalibrationSample>& samples,
                                 const std::vector<FitnessPose>& poses,
                                 const FitnessOptions& options = {});

// The probable cause of a failing figure from the pattern of its worst poses.
std::string FitnessCause(const CalibrationFitness& fitness);

// "slide 2000 mm, pan 10 deg, tilt 0 deg, 500 mA"
std::string PoseText(const FitnessPose& pose);

}  // namespace irdist
