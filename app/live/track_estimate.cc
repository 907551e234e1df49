#include "app/live/track_estimate.h"

#include <cmath>
#include <vector>

#include "app/processing/estimate_flags.h"
#include "base/pi.h"
#include "estimator/bracket_checks.h"
#include "estimator/estimate.h"
#include "estimator/estimate_baselines.h"
#include "estimator/health.h"
#include "estimator/theta_start.h"

namespace irdist {

namespace {

// The exposure's place in the range checks: a frame at a calibrated reference exposure is checked
// as a reference (t_ref_ms, no t_ms), any other as a measurement exposure (t_ms) beside a
// reference inside its range, so that only the frame's own exposure can be outside.
void ExposureRoles(const CalibratedRanges& ranges, double exposure_ms, double* t_ref_ms,
                   std::vector<double>* t_ms) {
  const bool reference = exposure_ms >= ranges.t_ref_min_ms * (1.0 - 1e-3) &&
                         exposure_ms <= ranges.t_ref_max_ms * (1.0 + 1e-3);
  *t_ref_ms = reference ? exposure_ms : ranges.t_ref_min_ms;
  if (!reference) t_ms->push_back(exposure_ms);
}

// The mean exposure of the calibration's measurement frames (the noise law's), from the model's
// provenance, else the middle of its measurement range; `fallback` when it records neither.
double CalibrationExposureMs(const CalibrationModel& model, double fallback) {
  const std::vector<double>& t_meas = model.provenance.t_meas_ms;
  if (!t_meas.empty()) {
    double sum = 0.0;
    for (double t : t_meas) sum += t;
    return sum / static_cast<double>(t_meas.size());
  }
  const CalibratedRanges& r = model.ranges;
  return r.t_max_ms > 0.0 ? 0.5 * (r.t_min_ms + r.t_max_ms) : fallback;
}

// theta (deg) of one frame: the fitted disc's axis ratio with the calibrated blur removed
// (estimator/theta_start.h, the start of the default estimator on a single frame).
double FrameThetaDeg(const CalibrationModel& model, const Features& f) {
  ThetaStartOptions options;
  options.from_features = false;
  options.bracket_moments = false;
  options.correction = false;
  return Theta0Combined(model, nullptr, 0, f, options);
}

// theta's standard error: the calibrated ellipse correction's scatter (as measure's bracket
// rows), NaN when the model has none.
double FrameThetaSeDeg(const CalibrationModel& model) {
  const ThetaCorrection& tc = model.theta_correction;
  return tc.fitted() ? std::sqrt(kPi / 2.0) * tc.summary.mean_relative_error : NAN;
}

// The row of one frame: distance, theta, their standard errors, ranges and flags.
EstimateRow FrameRow(const Features& f, double exposure_ms, const CalibrationModel& model,
                     const std::vector<const Features*>& health_frames, HealthCheck* health) {
  EstimateRow row;
  row.method = "track";
  const GeometricEstimate g = EstimateGeometric(model, f);
  row.ok = f.Usable() && g.valid && std::isfinite(g.d_mm) && g.d_mm > 0.0;
  DistanceEstimate e;
  e.d_mm = row.d_mm = row.ok ? g.d_mm : NAN;
  e.theta_deg = row.theta_deg = row.ok ? FrameThetaDeg(model, f) : NAN;
  e.d_std_mm = row.d_std_mm = row.ok ? FrameDistanceSeMm(model, g.d_mm, exposure_ms) : NAN;
  e.theta_std_deg = row.theta_std_deg = row.ok ? FrameThetaSeDeg(model) : NAN;
  double t_ref_ms = 0.0;
  std::vector<double> t_ms;
  ExposureRoles(model.ranges, exposure_ms, &t_ref_ms, &t_ms);
  const std::vector<const Features*> frames = {&f};
  if (row.ok) {
    row.outside = OutsideRanges(model.ranges, e, t_ref_ms, t_ms, frames, RangeOptionsOf(model));
    row.outside_range = !row.outside.empty();
    *health = CheckHealth(model, g.d_mm, health_frames.empty() ? frames : health_frames);
  }
  FlagRow(FrameFlags(frames), model.ranges, t_ms, row.ok ? health : nullptr, &row);
  return row;
}

}  // namespace

double FrameDistanceSeMm(const CalibrationModel& model, double d_mm, double exposure_ms) {
  const GeometricModel& g = model.geometric;
  const double noise = g.NoiseRel(d_mm);
  const double rel = noise > 0.0 ? noise : g.summary.mean_relative_error;
  if (!(rel > 0.0)) return NAN;
  return rel * d_mm * std::sqrt(CalibrationExposureMs(model, exposure_ms) / exposure_ms);
}

MeasureSample EstimateFrame(const Features& features, double exposure_ms,
                            const CalibrationModel& model, const CameraGeometry& geometry,
                            std::int64_t frame,
                            const std::vector<const Features*>& health_frames) {
  MeasureSample s;
  s.bracket = frame;
  const Features turned = OnLineOfSight(geometry, features);
  s.estimate = FrameRow(turned, exposure_ms, model, health_frames, &s.health);
  s.estimate.bracket = static_cast<int>(frame);
  s.have_estimate = true;
  s.blob_found = features.blob_found;
  s.blob_x_px = features.centroid_px.x + geometry.roi_offset_x;
  s.blob_y_px = features.centroid_px.y + geometry.roi_offset_y;
  s.saturated = features.saturated_pixels > 0;
  s.touches_border = features.touches_border;
  s.clipped = features.blob_clipped_by_roi;
  if (!s.estimate.ok || !geometry.intrinsics.known) return s;
  // One frame has no centroid scatter: the position's standard errors come from the range
  // alone (x and y NaN: PositionFromRange's rule for an unknown centre).
  const BlobPoint blob{s.blob_x_px, s.blob_y_px, NAN, NAN};
  const Position3d p =
      PositionFromRange(geometry.intrinsics, geometry.roi_offset_x, geometry.roi_offset_y, blob,
                        s.estimate.d_mm, s.estimate.d_std_mm);
  s.has_position = true;
  s.x_mm = p.x_mm;
  s.y_mm = p.y_mm;
  s.z_mm = p.z_mm;
  s.x_se_mm = p.x_se_mm;
  s.y_se_mm = p.y_se_mm;
  s.z_se_mm = p.z_se_mm;
  return s;
}

}  // namespace irdist
