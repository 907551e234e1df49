#include "app/processing/bracket_estimates.h"

#include <cmath>
#include <sstream>

#include "acquisition/recording_reader.h"
#include "app/processing/estimate_flags.h"
#include "app/processing/position.h"
#include "estimator/estimate.h"
#include "estimator/bracket_checks.h"
#include "estimator/estimate_baselines.h"
#include "estimator/health.h"
#include "estimator/models.h"
#include "estimator/refocus.h"

namespace irdist {

namespace {

// The health of an estimate at d_mm from its measurement frames (estimator/health.h).
HealthCheck HealthOfFrames(const CalibrationModel& model, double d_mm,
                           const std::vector<Features>& measurements) {
  std::vector<const Features*> frames;
  for (const Features& f : measurements) frames.push_back(&f);
  return CheckHealth(model, d_mm, frames);
}

// A row from estimate `e` of the exposures (t_ref_ms, t_ms) taken in `frames`: its values, the
// calibrated ranges it lies outside, and whether it is an estimate at all.
void FillRow(const CalibrationModel& model, const DistanceEstimate& e, double t_ref_ms,
             const std::vector<double>& t_ms, const std::vector<const Features*>& frames,
             EstimateRow* row) {
  row->d_mm = e.d_mm;
  row->theta_deg = e.theta_deg;
  row->d_std_mm = e.d_std_mm;
  row->theta_std_deg = e.theta_std_deg;
  row->outside = OutsideRanges(model.ranges, e, t_ref_ms, t_ms, frames, RangeOptionsOf(model));
  row->outside_range = !row->outside.empty();
  // A fallback start (no root of Eq. 25 in range) is not a failure when the solver converged
  // from it; a non-converged solve is.
  row->ok = std::isfinite(e.d_mm) && e.d_mm > 0.0 && e.converged;
}

// Motion inside the bracket of the joint row (estimator/bracket_checks.h): from the frames' own
// sizes and errors where the blob fit gave them (CheckMotionOfSizes), otherwise from the
// per-exposure rows against the joint one (CheckMotion).
MotionCheck MotionOfRows(const CalibrationModel& model, const std::vector<const Features*>& frames,
                         const std::vector<EstimateRow>& per_dt, EstimateRow* joint) {
  if (!joint->ok) return MotionCheck{};
  MotionCheck m = CheckMotionOfSizes(model.geometric, frames);
  if (!m.assessed) {
    std::vector<double> d_mm, d_se_mm;
    for (const EstimateRow& row : per_dt) {
      if (!row.ok) continue;
      d_mm.push_back(row.d_mm);
      d_se_mm.push_back(row.d_std_mm);
    }
    m = CheckMotion(joint->d_mm, d_mm, d_se_mm);
  }
  if (m.assessed) {
    joint->motion = m.moving ? "moving" : "static";
    joint->spread_mm = m.spread_mm;
  }
  return m;
}

// The rows of a bracket by one method before estimation: the joint (dt_ms = 0), then one per t_n.
std::vector<EstimateRow> EmptyRows(const std::string& method, const EstimateRow& base,
                                   const std::vector<DifferencePair>& pairs) {
  std::vector<EstimateRow> rows(1 + pairs.size(), base);
  for (size_t k = 0; k < rows.size(); ++k) {
    rows[k].method = method;
    rows[k].ok = false;
    rows[k].dt_ms = k == 0 ? 0.0
                           : (pairs[k - 1].measurement->requested_exposure_us -
                              pairs[k - 1].reference->requested_exposure_us) /
                                 1000.0;
  }
  return rows;
}

// Every frame of a bracket's pairs (a reference shared by pairs once) and its measurement
// exposures (ms), in pair order.
void FramesOfPairs(const std::vector<DifferencePair>& pairs, const FeatureMap& features,
                   std::vector<const Features*>* frames, std::vector<double>* t_ms) {
  const FrameRecord* last_reference = nullptr;
  for (const DifferencePair& pair : pairs) {
    if (pair.reference != last_reference) frames->push_back(&FeaturesOf(features, *pair.reference));
    last_reference = pair.reference;
    frames->push_back(&FeaturesOf(features, *pair.measurement));
    t_ms->push_back(pair.measurement->requested_exposure_us / 1000.0);
  }
}

// A row's standard errors grown by the bracket blur's: its change when the blur moves by its
// standard error (`shifted`, the estimate then), added in quadrature.
void GrowStandardErrors(const DistanceEstimate& shifted, EstimateRow* row) {
  if (!row->ok || !std::isfinite(shifted.d_mm) || !shifted.converged) return;
  if (row->d_std_mm >= 0.0) row->d_std_mm = std::hypot(row->d_std_mm, shifted.d_mm - row->d_mm);
  if (row->theta_std_deg >= 0.0) {
    row->theta_std_deg = std::hypot(row->theta_std_deg, shifted.theta_deg - row->theta_deg);
  }
}

// A refocused bracket's rows with the blur's uncertainty propagated (refocus.h): the estimate
// again from `shifted`, the features at the bracket's blur plus its standard error.
void AddBlurUncertainty(const CalibrationModel& model, const EstimateOptions& options,
                        const std::vector<DifferencePair>& pairs, const FeatureMap& shifted,
                        const std::vector<double>& t_ms, std::vector<EstimateRow>* rows) {
  const FrameRecord& reference = *pairs.front().reference;
  std::vector<Features> measurements;
  for (const DifferencePair& pair : pairs) {
    measurements.push_back(FeaturesOf(shifted, *pair.measurement));
  }
  const BracketEstimate e =
      EstimateBracket(model, FeaturesOf(shifted, reference),
                      reference.requested_exposure_us / 1000.0, measurements, t_ms, options);
  GrowStandardErrors(e.joint, &(*rows)[0]);
  for (size_t k = 0; k < pairs.size(); ++k) {
    if (pairs[k].reference == &reference) GrowStandardErrors(e.per_exposure[k], &(*rows)[k + 1]);
  }
}

// One method's rows for a bracket: the joint estimate (dt_ms = 0), then one row per t_n. With
// `checks`, the bracket's calibration health and motion (from this method's rows) go there.
// `shifted` (a refocused bracket): its features at its blur plus the blur's standard error.
void EstimateMethodRows(const CalibrationModel& model, const EstimateOptions& options,
                        const std::string& method, const EstimateRow& base,
                        const std::vector<DifferencePair>& pairs, const FeatureMap& features,
                        bool all_usable, std::vector<EstimateRow>* out,
                        BracketEstimateRows* checks = nullptr,
                        const FeatureMap* shifted = nullptr) {
  const FrameRecord& reference = *pairs.front().reference;
  std::vector<const Features*> frames;  // every frame of the bracket, for the signal's range
  std::vector<double> t_ms;
  FramesOfPairs(pairs, features, &frames, &t_ms);
  std::vector<Features> measurements;
  for (const DifferencePair& pair : pairs) {
    measurements.push_back(FeaturesOf(features, *pair.measurement));
  }
  std::vector<EstimateRow> rows = EmptyRows(method, base, pairs);
  DistanceEstimate none;  // without an estimate: the exposures' and the signal's ranges only
  none.d_mm = none.theta_deg = NAN;
  rows[0].outside = OutsideRanges(model.ranges, none, reference.requested_exposure_us / 1000.0,
                                  t_ms, frames);
  rows[0].outside_range = !rows[0].outside.empty();
  if (all_usable && measurements.size() <= static_cast<size_t>(kMaxBracketExposures)) {
    const double t_ref_ms = reference.requested_exposure_us / 1000.0;
    const BracketEstimate estimate = EstimateBracket(model, FeaturesOf(features, reference),
                                                     t_ref_ms, measurements, t_ms, options);
    FillRow(model, estimate.joint, t_ref_ms, t_ms, frames, &rows[0]);
    const HealthCheck health = HealthOfFrames(model, estimate.joint.d_mm, measurements);
    rows[0].health = health.Label();
    for (size_t k = 0; k < pairs.size(); ++k) {
      // Each t_n with the reference it is differenced with (interleaved brackets).
      const Features& ref = FeaturesOf(features, *pairs[k].reference);
      const double ref_ms = pairs[k].reference->requested_exposure_us / 1000.0;
      const DistanceEstimate e =
          pairs[k].reference == &reference
              ? estimate.per_exposure[k]
              : EstimatePair(model, ref, ref_ms, measurements[k], t_ms[k], options);
      FillRow(model, e, ref_ms, {t_ms[k]}, {&ref, &measurements[k]}, &rows[k + 1]);
    }
    const MotionCheck motion = MotionOfRows(
        model, frames, std::vector<EstimateRow>(rows.begin() + 1, rows.end()), &rows[0]);
    if (shifted != nullptr) AddBlurUncertainty(model, options, pairs, *shifted, t_ms, &rows);
    if (checks != nullptr) {
      checks->health = health;
      checks->motion = motion;
    }
  }
  out->insert(out->end(), rows.begin(), rows.end());
}

}  // namespace

namespace {

// The I0-dependent comparison's row of a bracket; it assumes the calibration's mean current.
EstimateRow I0DependentRow(const CalibrationModel& model, const EstimateRow& base,
                           const std::vector<DifferencePair>& pairs, const FeatureMap& features,
                           bool all_usable) {
  EstimateRow row = base;
  row.method = "i0_dependent";
  row.ok = false;
  if (!all_usable) return row;
  std::vector<Features> measurements;
  std::vector<double> t_ms;
  for (const DifferencePair& pair : pairs) {
    measurements.push_back(FeaturesOf(features, *pair.measurement));
    t_ms.push_back(pair.measurement->requested_exposure_us / 1000.0);
  }
  const FrameRecord& reference = *pairs.front().reference;
  const I0DependentEstimate e =
      EstimateI0Dependent(model, FeaturesOf(features, reference),
                          reference.requested_exposure_us / 1000.0, measurements, t_ms,
                          model.scaling.i0_scale_ma);
  row.ok = e.valid;
  row.d_mm = e.d_mm;
  row.theta_deg = e.theta_deg;
  row.outside_range = e.outside_calibrated_range;
  if (row.outside_range) row.outside = {"distance"};
  return row;
}

// Geometric baseline: the mean over the measurement frames; theta from their ellipses.
EstimateRow GeometricRow(const CalibrationModel& model, const EstimateRow& base,
                         const std::vector<DifferencePair>& pairs, const FeatureMap& features) {
  EstimateRow row = base;
  row.method = "geometric";
  double sum_d = 0.0, sum_theta = 0.0;
  int n = 0;
  bool outside = false;
  for (const DifferencePair& pair : pairs) {
    const Features& f = FeaturesOf(features, *pair.measurement);
    if (!f.Usable()) continue;
    const GeometricEstimate g = EstimateGeometric(model, f);
    if (!g.valid) continue;
    sum_d += g.d_mm;
    sum_theta += f.theta0_deg;
    outside = outside || g.outside_calibrated_range;
    ++n;
  }
  row.ok = n > 0;
  row.d_mm = n > 0 ? sum_d / n : 0.0;
  row.theta_deg = n > 0 ? sum_theta / n : 0.0;
  row.outside_range = outside;
  if (outside) row.outside = {"distance"};
  return row;
}

// The bracket's row before estimation: its ids and ground truth. The truth is the geometry of
// the recorded pose; a recording without pan and tilt (NaN) keeps its slide and theta.
EstimateRow BaseRowOf(const RecordedBracket& bracket, const FrameRecord& first,
                      const CameraGeometry& geometry) {
  EstimateRow base;
  base.bracket = static_cast<int>(bracket.bracket_id);
  base.pose = static_cast<int>(bracket.bracket_id);
  base.repeat = first.repeat;
  base.true_d_mm = first.slide_mm;
  base.true_theta_deg = first.theta_deg;
  base.bias_ma = first.bias_ma_set;
  // The bracket's time: its last frame's arrival (the estimate's data complete then).
  const FrameRecord& last = bracket.frames.back();
  base.utc_ns = last.host_time_ns;
  base.host_monotonic_ns = last.host_monotonic_ns;
  base.camera_timestamp_ns = last.camera_timestamp_ns;
  const TrueGeometry truth =
      TrueGeometryOf(geometry, first.slide_mm, first.pan_deg, first.tilt_deg);
  if (std::isfinite(truth.d_mm)) {
    base.true_d_mm = truth.d_mm;
    base.true_theta_deg = truth.theta_deg;
    base.true_x_mm = truth.x_mm;
    base.true_y_mm = truth.y_mm;
    base.true_z_mm = truth.z_mm;
  }
  return base;
}

}  // namespace

namespace {

// The blob's centre in the sensor's pixels: the mean centroid of the measurement frames (NaN
// when some frame has no blob), with the standard error of that mean from their scatter (NaN
// with one frame).
BlobPoint BlobOf(const std::vector<DifferencePair>& pairs, const FeatureMap& features,
                 const CameraGeometry& geometry) {
  std::vector<cv::Point2d> centroids;
  for (const DifferencePair& pair : pairs) {
    const Features& f = FeaturesOf(features, *pair.measurement);
    if (!f.blob_found) return BlobPoint{NAN, NAN, NAN, NAN};
    centroids.push_back(f.centroid_px);
  }
  const double n = static_cast<double>(centroids.size());
  cv::Point2d mean(0.0, 0.0);
  for (const cv::Point2d& c : centroids) mean += c / n;
  BlobPoint blob{mean.x + geometry.roi_offset_x, mean.y + geometry.roi_offset_y, NAN, NAN};
  if (centroids.size() < 2) return blob;
  double su = 0.0, sv = 0.0;
  for (const cv::Point2d& c : centroids) {
    su += (c.x - mean.x) * (c.x - mean.x);
    sv += (c.y - mean.y) * (c.y - mean.y);
  }
  blob.u_se_px = std::sqrt(su / (n - 1.0) / n);
  blob.v_se_px = std::sqrt(sv / (n - 1.0) / n);
  return blob;
}

// The flags of every row (app/processing/estimate_flags.h): the frames' for all, each row's own
// ranges (a joint row over every t_n, a per-t_n row over its own), motion, and the default
// method's health on its joint row.
void FlagRows(const CalibrationModel& model, const std::vector<DifferencePair>& pairs,
              const FeatureMap& features, BracketEstimateRows* rows) {
  std::vector<const Features*> frames;
  std::vector<double> t_ms;
  FramesOfPairs(pairs, features, &frames, &t_ms);
  const BracketFrameFlags frame_flags = FrameFlags(frames);
  const EstimateRow* size = rows->geometric.empty() ? nullptr : &rows->geometric.front();
  for (auto* block : {&rows->i0_free, &rows->paper, &rows->i0_dependent, &rows->geometric}) {
    for (size_t k = 0; k < block->size(); ++k) {
      EstimateRow& row = (*block)[k];
      const bool per_dt = row.dt_ms != 0.0 && k >= 1 && k - 1 < t_ms.size();
      const HealthCheck* health = block == &rows->i0_free && k == 0 ? &rows->health : nullptr;
      FlagRow(frame_flags, model.ranges, per_dt ? std::vector<double>{t_ms[k - 1]} : t_ms, health,
              &row);
      // The radiometric methods' joint rows against the blob's size, an independent reading.
      const bool radiometric = block == &rows->i0_free || block == &rows->paper;
      if (radiometric && k == 0 && size != nullptr) {
        FlagDisagreement(*size, DisagreementTolerance(model), &row);
      }
    }
  }
}

}  // namespace

namespace {

// The blob-fit health of a bracket's measurement frames before its estimate (estimator/health.h):
// flagged, the bracket is estimated with its own blur (refocused).
HealthCheck BlurBeforeEstimate(const CalibrationModel& model,
                               const std::vector<DifferencePair>& pairs,
                               const FeatureMap& features) {
  std::vector<const Features*> frames;
  for (const DifferencePair& pair : pairs) frames.push_back(&FeaturesOf(features, *pair.measurement));
  return CheckHealth(model, NAN, frames);
}

// Every frame of the bracket with its blob's size at `blur_var_px2` (refocus.h AtBlur).
FeatureMap BracketAtBlur(const RecordedBracket& bracket, const FeatureMap& features,
                         double blur_var_px2) {
  FeatureMap out;
  for (const FrameRecord& row : bracket.frames) {
    const auto f = features.find(row.index);
    if (f != features.end()) out[row.index] = AtBlur(f->second, blur_var_px2);
  }
  return out;
}

}  // namespace

BracketEstimateRows EstimateRecordedBracket(const RecordedBracket& bracket,
                                            const FeatureMap& frame_features,
                                            const CalibrationModel& model,
                                            const CameraGeometry& geometry) {
  BracketEstimateRows rows;
  if (!bracket.complete) return rows;
  const std::vector<DifferencePair> pairs = DifferencePairsOf(bracket);
  if (pairs.empty()) return rows;
  // A focus change since calibration, measured through: the bracket's own blur where its
  // blob-fit blur departs from the calibrated one (estimator/refocus.h).
  const HealthCheck blur = BlurBeforeEstimate(model, pairs, frame_features);
  const bool refocus = blur.blob_fit && blur.flagged;
  const FeatureMap features = BracketOnLineOfSight(
      bracket, refocus ? BracketAtBlur(bracket, frame_features, blur.blur_var_px2) : frame_features,
      geometry);
  const FeatureMap shifted =
      refocus ? BracketOnLineOfSight(
                    bracket,
                    BracketAtBlur(bracket, frame_features, blur.blur_var_px2 + blur.blur_se_px2),
                    geometry)
              : FeatureMap{};
  const FeatureMap* blur_shifted = refocus ? &shifted : nullptr;
  const EstimateRow base = BaseRowOf(bracket, *pairs.front().measurement, geometry);
  bool all_usable = true;
  for (const DifferencePair& pair : pairs) {
    all_usable = all_usable && FeaturesOf(features, *pair.reference).Usable() &&
                 FeaturesOf(features, *pair.measurement).Usable();
  }
  EstimateMethodRows(model, EstimateOptions{}, "i0_free", base, pairs, features, all_usable,
                     &rows.i0_free, &rows, blur_shifted);
  rows.health.refocused = refocus && rows.health.blob_fit && rows.health.flagged;
  EstimateMethodRows(model, PaperEstimateOptions(), "paper", base, pairs, features, all_usable,
                     &rows.paper, nullptr, blur_shifted);
  if (model.Find(ModelKind::kDiffF) != nullptr) {
    rows.i0_dependent.push_back(I0DependentRow(model, base, pairs, features, all_usable));
  }
  if (model.geometric.fitted()) rows.geometric.push_back(GeometricRow(model, base, pairs, features));
  AddPositions(geometry, BlobOf(pairs, features, geometry),
               {&rows.i0_free, &rows.paper, &rows.i0_dependent, &rows.geometric});
  FlagRows(model, pairs, features, &rows);
  return rows;
}

std::vector<EstimateRow> FlattenRows(const BracketEstimateRows& bracket) {
  std::vector<EstimateRow> rows = bracket.i0_free;
  for (const auto* block : {&bracket.paper, &bracket.i0_dependent, &bracket.geometric}) {
    rows.insert(rows.end(), block->begin(), block->end());
  }
  return rows;
}

std::vector<std::string> ModelFitnessWarnings(const CalibrationModel& model,
                                              const std::string& model_path) {
  std::vector<std::string> out;
  const std::string head = "warning: model fitness (";
  if (!model.provenance.known) {
    out.push_back(head + "no_provenance): " + model_path +
                  " has no provenance: block, so its camera, ROI and bracket cannot be checked "
                  "against this one. Recalibrate with this build (irdist calibrate) to record it.");
  } else if (model.provenance.camera_serial.empty()) {
    out.push_back(head + "blank_serial): " + model_path +
                  " names no camera serial (provenance.camera_serial is blank), so it is accepted "
                  "for any camera. Write the calibration camera's serial there, or recalibrate.");
  }
  if (!model.blur_calibration.fitted()) {
    out.push_back(head + "no_fingerprint): " + model_path +
                  " has no calibrated blur (blur_calibration), the optics' fingerprint: neither "
                  "its optics nor the calibration's health can be checked. Recalibrate with this "
                  "build.");
  }
  return out;
}

std::string OpticsFingerprintWarning(const CalibrationModel& model, const HealthCheck& first,
                                     double d_mm) {
  if (!first.assessed || !first.flagged) return "";
  const CalibratedRanges& r = model.ranges;
  std::ostringstream out;
  out.precision(3);
  out << "warning: model fitness (optics_differ): the first bracket's blur is " << first.blur_var_px2
      << " px^2 at " << std::lround(d_mm) << " mm, the model's " << first.calibrated_px2
      << " px^2 there (its fingerprint:";
  for (double d : {r.d_min_mm, 0.5 * (r.d_min_mm + r.d_max_mm), r.d_max_mm}) {
    const BlurCalibration& b = model.blur_calibration;
    out << " " << std::lround(d) << " mm " << (first.blob_fit ? b.FitBlurVarPx2(d) : b.BlurVarPx2(d))
        << " px^2";
  }
  out << "). The model was calibrated with other optics (another rig with this camera, another "
         "lens or focus): use that rig's model, restore the focus, or recalibrate.";
  return out.str();
}

std::string MotionWarning(int moving, int brackets) {
  return std::to_string(moving) + " of " + std::to_string(brackets) +
         " brackets flagged moving: their per-exposure distances disagree beyond their noise, "
         "the IRED moved while the bracket was taken. Hold it still during a bracket (a station "
         "settles after each move), or discard those estimates";
}

RecordingEstimates EstimateRecording(const RecordingReader& reader, const FeatureMap& features,
                                     const CalibrationModel& model) {
  RecordingEstimates out;
  HealthCheck health;
  const CameraGeometry geometry = GeometryOfRecording(reader);
  int brackets = 0, moving = 0;
  bool fingerprint_checked = false;
  for (const RecordedBracket& bracket : reader.Brackets()) {
    const BracketEstimateRows rows = EstimateRecordedBracket(bracket, features, model, geometry);
    if (rows.health.assessed && !fingerprint_checked) {
      fingerprint_checked = true;
      const std::string warning =
          OpticsFingerprintWarning(model, rows.health, rows.i0_free.front().d_mm);
      if (!warning.empty()) out.warnings.push_back(warning);
    }
    if (rows.health.flagged && !health.flagged) health = rows.health;
    brackets += rows.i0_free.empty() ? 0 : 1;
    moving += rows.motion.moving ? 1 : 0;
    const std::vector<EstimateRow> flat = FlattenRows(rows);
    out.rows.insert(out.rows.end(), flat.begin(), flat.end());
  }
  if (health.flagged) {  // once per recording
    out.warnings.push_back("warning: calibration health: " + health.Advice() +
                           " (estimates.csv column health).");
  }
  if (moving > 0) {
    out.warnings.push_back("warning: " + MotionWarning(moving, brackets) +
                           " (estimates.csv columns motion, spread_mm).");
  }
  return out;
}

}  // namespace irdist
