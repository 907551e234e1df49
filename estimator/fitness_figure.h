#pragma once
// The fit's fitness figure (model.yaml key `fitness`): the plain result of AssessFitness
// (estimator/fitness.h, which computes it) and its text. Apart from fitness.h so that
// CalibrationModel (estimator/fit.h) can hold a figure without the computation that needs the model.

#include <string>
#include <vector>

namespace irdist {

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

// The probable cause of a failing figure from the pattern of its worst poses.
std::string FitnessCause(const CalibrationFitness& fitness);

// "slide 2000 mm, pan 10 deg, tilt 0 deg, 500 mA"
std::string PoseText(const FitnessPose& pose);

}  // namespace irdist
