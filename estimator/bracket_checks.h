#pragma once
// The checks of a bracket's estimate that say whether to trust it: motion inside the bracket
// (its frames' sizes, or its per-exposure distances, against their noise) and the calibrated
// ranges it lies outside (distance, theta, exposures, signal). Used by validate, playback, measure
// and the Python module (app/processing/bracket_estimates.cc) beside the calibration's health
// (health.h).

#include <string>
#include <vector>

#include "estimator/estimate.h"
#include "estimator/features.h"
#include "estimator/fit.h"

namespace irdist {

// Motion inside a bracket: an IRED that moves while the bracket's exposures are taken gives
// per-exposure distances that disagree beyond their noise. chi2 = sum ((d_n - d_joint) / se_n)^2
// over the per-exposure estimates with a standard error, against the chi-square quantile with
// n - 1 degrees of freedom (the joint estimate is fitted to the same frames) at 1 -
// false_alarm. The per-exposure estimates share the reference frame, which moves them together
// and leaves the test conservative on a static IRED (docs/estimator.md, "Motion").
struct MotionOptions {
  double false_alarm = 1e-3;  // probability of flagging a static bracket, at the nominal noise
  // The first problem, naming the field, in *why (empty when valid).
  bool IsValid(std::string* why) const;
};
struct MotionCheck {
  bool assessed = false;  // >= 2 estimates (exposures or frames) with a standard error
  int exposures = 0;  // how many estimates entered (the frames for CheckMotionOfSizes)
  double chi2 = 0.0;
  double chi2_limit = 0.0;  // the quantile it is compared with
  double spread_mm = 0.0;   // largest minus smallest of the distances
  bool moving = false;
};
// `d_mm` and `d_se_mm` per exposure (a se <= 0 or NaN, or a non-finite d, leaves that exposure
// out); `joint_d_mm` the joint estimate's distance.
MotionCheck CheckMotion(double joint_d_mm, const std::vector<double>& d_mm,
                        const std::vector<double>& d_se_mm,
                        const MotionOptions& options = MotionOptions());

// Motion from the frames' own sizes, the default where the blob fit gave every frame of the
// bracket (the reference included) its trace size with a standard error from the frame's own
// noise (Features::trace_var_px2, _se_px2; estimator/blob_fit.h): each size put on the major
// axis by the bracket's common major-to-trace ratio, its geometric distance
// (GeometricModel::DistanceMm) and standard error through the model's slope, then CheckMotion
// about their inverse-variance weighted mean (n - 1 degrees of freedom, exactly). The noise is
// each frame's own, so the law holds at every pose: the per-exposure estimates' standard errors
// come from the calibration's noise law, a function of d alone (1.5x too small at theta 25 deg
// with a small calibration grid, docs/measure.md "False alarms"). Not assessed when a frame
// lacks a trace size.
MotionCheck CheckMotionOfSizes(const GeometricModel& geometric,
                               const std::vector<const Features*>& frames,
                               const MotionOptions& options = MotionOptions());

// Which calibrated ranges (model.yaml `ranges:`) a bracket's estimate lies outside, by name:
// "distance", "theta" (each edge widened by z_limit x the estimate's own standard error, the
// distance's combined with the calibration's own relative error, so a reading at the
// calibration's edge is inside), "t_ref", "t_meas" (every exposure of the bracket,
// against the calibrated reference and measurement exposures, to 0.1%) and "signal" (the peak
// gray level of the bracket's frames against the calibration frames', to 2%; skipped for models
// without a `ranges.peak`). Empty: inside every range.
struct RangeOptions {
  double z_limit = 3.0;
  // The calibration's relative distance error (e.g. the geometric fit's mean relative error),
  // added in quadrature to the distance's standard error: a systematic error the estimate's own
  // noise does not show.
  double calibration_rel_error = 0.0;
  double exposure_tolerance = 1e-3;  // relative
  double signal_tolerance = 0.02;    // relative
  // The first problem, naming the field, in *why (empty when valid).
  bool IsValid(std::string* why) const;
};
// The range check's options for `model`: its geometric fit's mean relative error (what the
// distance leans on) as the calibration's error, beside each estimate's own.
RangeOptions RangeOptionsOf(const CalibrationModel& model);

std::vector<std::string> OutsideRanges(const CalibratedRanges& ranges,
                                       const DistanceEstimate& estimate, double t_ref_ms,
                                       const std::vector<double>& t_ms,
                                       const std::vector<const Features*>& frames,
                                       const RangeOptions& options = RangeOptions());

}  // namespace irdist
