#include "estimator/bracket_checks.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <boost/math/distributions/chi_squared.hpp>

#include "base/check.h"

namespace irdist {

bool MotionOptions::IsValid(std::string* why) const {
  std::string reason;
  if (!(false_alarm > 0.0 && false_alarm < 1.0)) reason = "false_alarm not in (0, 1)";
  if (why != nullptr) *why = reason;
  return reason.empty();
}

bool RangeOptions::IsValid(std::string* why) const {
  std::string reason;
  if (!(z_limit > 0.0 && z_limit <= 100.0)) {
    reason = "z_limit not in (0, 100] standard errors";
  } else if (!(calibration_rel_error >= 0.0 && calibration_rel_error < 1.0)) {
    reason = "calibration_rel_error not in [0, 1)";
  } else if (!(exposure_tolerance > 0.0 && exposure_tolerance < 1.0)) {
    reason = "exposure_tolerance not in (0, 1)";
  } else if (!(signal_tolerance > 0.0 && signal_tolerance < 1.0)) {
    reason = "signal_tolerance not in (0, 1)";
  }
  if (why != nullptr) *why = reason;
  return reason.empty();
}

MotionCheck CheckMotion(double joint_d_mm, const std::vector<double>& d_mm,
                        const std::vector<double>& d_se_mm, const MotionOptions& options) {
  IRDIST_CHECK(d_mm.size() == d_se_mm.size(), "d_mm and d_se_mm differ in length");
  std::string why;
  IRDIST_CHECK(options.IsValid(&why), "MotionOptions: " + why);
  MotionCheck m;
  if (!std::isfinite(joint_d_mm)) return m;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (size_t i = 0; i < d_mm.size(); ++i) {
    if (!std::isfinite(d_mm[i]) || !(d_se_mm[i] > 0.0) || !std::isfinite(d_se_mm[i])) continue;
    const double z = (d_mm[i] - joint_d_mm) / d_se_mm[i];
    m.chi2 += z * z;
    lo = std::min(lo, d_mm[i]);
    hi = std::max(hi, d_mm[i]);
    ++m.exposures;
  }
  if (m.exposures < 2) return MotionCheck{};
  m.assessed = true;
  m.spread_mm = hi - lo;
  const boost::math::chi_squared law(m.exposures - 1);
  m.chi2_limit = boost::math::quantile(boost::math::complement(law, options.false_alarm));
  m.moving = m.chi2 > m.chi2_limit;
  return m;
}

namespace {

// A frame's trace size and its standard error, false when it has none.
bool HasTraceSize(const Features& f) {
  return f.blob_found && std::isfinite(f.trace_var_px2) && f.trace_var_se_px2 > 0.0 &&
         std::isfinite(f.trace_var_se_px2) && f.trace_var_px2 > f.trace_var_se_px2 &&
         f.moment_major_var_px2 > 0.0;
}

}  // namespace

MotionCheck CheckMotionOfSizes(const GeometricModel& geometric,
                               const std::vector<const Features*>& frames,
                               const MotionOptions& options) {
  if (!geometric.fitted() || frames.size() < 2) return MotionCheck{};
  // The bracket's major-to-trace ratio (its ellipse's shape, common to its frames) puts each
  // trace size on the major axis the geometric model reads.
  double w_major = 0.0, w_trace = 0.0;
  for (const Features* f : frames) {
    if (!HasTraceSize(*f)) return MotionCheck{};
    const double w = 1.0 / (f->trace_var_se_px2 * f->trace_var_se_px2);
    w_major += w * f->moment_major_var_px2;
    w_trace += w * f->trace_var_px2;
  }
  const double ratio = w_major / w_trace;
  std::vector<double> d_mm, d_se_mm;
  double sum_w = 0.0, sum_wd = 0.0;
  for (const Features* f : frames) {
    const double var = ratio * f->trace_var_px2, se = ratio * f->trace_var_se_px2;
    const double d = geometric.DistanceMm(var);
    const double se_mm = geometric.DistanceSeMm(var, se);
    if (!std::isfinite(d) || !(se_mm > 0.0)) return MotionCheck{};
    d_mm.push_back(d);
    d_se_mm.push_back(se_mm);
    sum_w += 1.0 / (se_mm * se_mm);
    sum_wd += d / (se_mm * se_mm);
  }
  return CheckMotion(sum_wd / sum_w, d_mm, d_se_mm, options);
}

std::vector<std::string> OutsideRanges(const CalibratedRanges& ranges,
                                       const DistanceEstimate& estimate, double t_ref_ms,
                                       const std::vector<double>& t_ms,
                                       const std::vector<const Features*>& frames,
                                       const RangeOptions& options) {
  std::string why;
  IRDIST_CHECK(options.IsValid(&why), "RangeOptions: " + why);
  std::vector<std::string> outside;
  DistanceEstimate widened = estimate;  // the distance's se with the calibration's error
  const double calibration_mm = options.calibration_rel_error * estimate.d_mm;
  widened.d_std_mm = std::hypot(std::max(estimate.d_std_mm, 0.0), calibration_mm);
  if (ranges.DistanceOutside(widened.d_mm, widened.d_std_mm, options.z_limit)) {
    outside.push_back("distance");
  }
  if (ranges.ThetaOutside(estimate.theta_deg, estimate.theta_std_deg, options.z_limit)) {
    outside.push_back("theta");
  }
  const auto beyond = [](double value, double lo, double hi, double tolerance) {
    return value < lo * (1.0 - tolerance) || value > hi * (1.0 + tolerance);
  };
  if (beyond(t_ref_ms, ranges.t_ref_min_ms, ranges.t_ref_max_ms, options.exposure_tolerance)) {
    outside.push_back("t_ref");
  }
  for (double t : t_ms) {
    if (beyond(t, ranges.t_min_ms, ranges.t_max_ms, options.exposure_tolerance)) {
      outside.push_back("t_meas");
      break;
    }
  }
  if (ranges.peak_max > 0.0) {
    for (const Features* f : frames) {
      if (f != nullptr && f->blob_found &&
          beyond(f->peak, ranges.peak_min, ranges.peak_max, options.signal_tolerance)) {
        outside.push_back("signal");
        break;
      }
    }
  }
  return outside;
}

RangeOptions RangeOptionsOf(const CalibrationModel& model) {
  RangeOptions options;
  if (model.geometric.fitted()) {
    options.calibration_rel_error = std::max(model.geometric.summary.mean_relative_error, 0.0);
  }
  return options;
}

}  // namespace irdist
