#pragma once
// The estimates the I0-free method is compared with, for the reports (validate's summary, the
// accuracy study): the geometric baseline (the blob's size alone) and the I0-dependent
// differential F model read at an assumed current.

#include <string>
#include <vector>

#include "estimator/features.h"
#include "estimator/fit.h"

namespace irdist {

struct GeometricEstimate {
  bool valid = false;  // a blob with a second moment above the calibrated blur
  double d_mm = 0.0;
  bool outside_calibrated_range = false;
  std::string BriefReport() const;
};

// The geometric baseline (fit.h, GeometricModel) on one frame's features.
GeometricEstimate EstimateGeometric(const CalibrationModel& model, const Features& features);

// The I0-DEPENDENT comparison: the differential F model (Eq. 11, kDiffF) read at an assumed bias
// current (the nominal one), theta from the ellipse, d by least squares on the relative residuals
// of every t_n of the bracket (dF is linear in D at fixed theta: closed form). It is what the
// I0-free method is meant to beat: any change of the radiant intensity (self-heating, another
// current) biases it by half the relative change.
struct I0DependentEstimate {
  bool valid = false;  // a fitted diff_f model, usable frames and a positive D
  double d_mm = 0.0;
  double theta_deg = 0.0;  // the ellipse's (not solved)
  double assumed_bias_ma = 0.0;
  bool outside_calibrated_range = false;
  std::string BriefReport() const;
};

I0DependentEstimate EstimateI0Dependent(const CalibrationModel& model, const Features& reference,
                                        double t_ref_ms, const std::vector<Features>& measurements,
                                        const std::vector<double>& t_ms, double assumed_bias_ma);

}  // namespace irdist
