#pragma once
// Calibration health: does a measurement still see the optics the calibration saw? Where the
// frames carry the blob fit's own blur (features.h own_blur_var_px2, estimator/refocus.h: the
// blur that fits each frame best within the blob family the calibration fitted its blur with), the
// bracket's joint blob-fit blur is compared with the calibrated blob-fit blur (BlurCalibration::
// FitBlurVarPx2, the blur the blob fit was given): a lens outside the Gaussian family (a halo, an
// astigmatic PSF) under its own calibration reads as calibrated, and a real focus change is seen
// (and measured through: bracket_estimates.cc `refocused`). Without it (the moments path), the
// blob's cumulant blur (Features::blur_var_px2: 2nd and 4th cumulants along its axes) against the
// calibrated cumulant blur at the estimated distance. A touched focus ring, a lens swap or a
// temperature change moves the blur; the geometric (size) model then reads the wrong distance
// unless the bracket's own blur is used. docs/estimator.md.

#include <string>
#include <vector>

#include "estimator/blur_model.h"  // BlurCalibration, for the includers of this header

namespace irdist {

struct CalibrationModel;   // fit.h
struct Features;           // features.h

struct HealthOptions {
  // Flag when the mean measured blur variance departs from the calibrated one by more than
  // z_limit standard errors (per-frame sd / sqrt(frames)) AND by more than
  // min_sigma_change of the blur's sigma (the second keeps a long bracket from flagging changes
  // too small to matter). Chosen on the virtual rig (docs/estimator.md): 0 false flags over the
  // three validation recipes, a 15% blur change flagged in >= 95% of estimates.
  double z_limit = 5.0;
  double min_sigma_change = 0.05;
  // The first problem, naming the field, in *why (empty when valid).
  bool IsValid(std::string* why) const;
};

struct HealthCheck {
  bool assessed = false;         // a calibrated blur and at least one frame with a measured blur
  int frames = 0;                // frames with a measured blur
  double blur_var_px2 = 0.0;     // their mean measured blur variance
  double calibrated_px2 = 0.0;   // the calibrated blur variance at the estimated distance
  double sigma_change = 0.0;     // relative change of the blur's sigma (pixel area removed)
  double z = 0.0;                // departure in standard errors
  bool flagged = false;
  // The figure: true = the blob fit's own blur against the calibrated blob-fit blur (its standard
  // error blur_se_px2 from the frames' fits), false = the cumulants' blur.
  bool blob_fit = false;
  double blur_se_px2 = 0.0;
  // Set by the estimate (app/processing/bracket_estimates.cc): the bracket was estimated with its
  // own blur (flagged on the blob-fit figure), the `refocused` flag.
  bool refocused = false;
  // "ok", "-" (not assessed), "blur_larger" or "blur_smaller" (the estimates.csv health column).
  const char* Label() const;
  // What to do when flagged ("" when not): refocus to the calibration's focus, or recalibrate.
  std::string Advice() const;
};

// The relative change of the blur's sd, the pixel's area removed, from the calibrated blur
// variance to the measured one (both pixel area included): HealthCheck::sigma_change.
double BlurSigmaChange(double measured_var_px2, double calibrated_var_px2);

// The health of one estimate at distance d_mm from its measurement frames: the blob-fit figure
// where every usable frame has an own blur (d_mm then unused: each frame's calibrated blur is
// the one its blob fit was given), else the cumulants' at d_mm.
HealthCheck CheckHealth(const CalibrationModel& model, double d_mm,
                        const std::vector<const Features*>& frames,
                        const HealthOptions& options = HealthOptions());

}  // namespace irdist
