#pragma once
// The flags of a bracket's estimates (docs/reports.md, "Flags"): every cause that makes an
// estimate suspect, named with its figure, and the notes of what it was measured through, the
// same for validate, playback, measure and the Python module (EstimateRecordedBracket sets them).
// A bracket's frames give the scene's flags (the scene pass of estimator/scene.h: defect pixels,
// other blobs, a second source, an occluded disc; saturation, the window's border); each row adds
// its own ranges, motion and calibration health.

#include <cmath>
#include <string>
#include <vector>

#include "app/processing/estimates_csv.h"
#include "estimator/features.h"
#include "estimator/fit.h"
#include "estimator/health.h"

namespace irdist {

// How far beyond the calibrated measurement exposures an exposure is still a graded note
// (`t_meas_extrapolated`) and not `outside`: relative to the nearest calibrated edge. The I0-free
// models are low-order polynomials in dt, and a linear camera's signal is proportional to the
// exposure: Fig. 10's 38 and 40 ms (11% beyond Table 3's 36 ms) measure as well as 30-36 ms
// (docs/estimator.md, "Exposures beyond the calibration").
constexpr double kExposureExtrapolation = 0.15;

// How far beyond the calibration frames' peak levels (model.yaml ranges.peak) a bracket's peak is
// still a graded note (`signal_extrapolated`) and not `outside`: relative to the nearest edge. The
// features are linear in the signal on a linear camera (the response the calibration fits);
// Fig. 10's 525 mA at 40 ms (up to 17% above Table 3's brightest frame) measures as well as the
// brackets inside (docs/estimator.md, "Exposures beyond the calibration").
constexpr double kSignalExtrapolation = 0.25;

// The worst of each scene figure over a bracket's frames (a frame without a blob counts in
// no_blob): what the flags and `irdist check` (scene_check.h) say of a bracket.
struct SceneFigures {
  int frames = 0, no_blob = 0;
  int saturated_frames = 0, saturated_px = 0;  // frames with saturation; the most pixels in one
  int defect_pixels = 0, other_blobs = 0;       // the most in one frame
  int second_source = 0, occluded = 0;          // frames
  bool touches_border = false, clipped = false;
  double second_source_gap_px = NAN;  // the smallest gap over the frames with a second source
  double occluded_edge_fraction = 0.0;
  double peak_min = 0.0, peak_max = 0.0;  // over the frames with a blob (0: none)
  double background_max = 0.0;           // the frames' background, normalised
  void Add(const Features* f);           // null: a frame without features (no blob)
};

// What a bracket's frames (every frame: references and measurements) say, the same for each of
// its rows: the scene's and the frames' flags, notes (defect_pixels, other_blobs) and suspects
// (no_blob, saturated, touches_border, clipped, second_source, occluded), each with the worst
// figure over the frames; and the frames' blob peak levels (normalised).
struct BracketFrameFlags {
  std::vector<EstimateFlag> flags;
  double peak_min = 0.0, peak_max = 0.0;  // over the frames with a blob (0: none)
};
BracketFrameFlags FrameFlags(const std::vector<const Features*>& frames);

// A row's range, motion and health flags on top of its frames': `outside` with its ranges, except
// a `t_meas` within kExposureExtrapolation of the calibrated exposures (`t_ms`, the row's
// measurement exposures) and a `signal` within kSignalExtrapolation of the calibrated peaks, which
// become the notes `t_meas_extrapolated` and `signal_extrapolated` and leave the row's outside
// list and outside_range; `moving` with the spread; `blur_larger`/`blur_smaller` with the blur's
// change when `health` is given and flagged, or the note `refocused` with it when the bracket was
// measured with its own blur (HealthCheck::refocused); `no_estimate` on a row without an estimate.
void FlagRow(const BracketFrameFlags& frames, const CalibratedRanges& ranges,
             const std::vector<double>& t_ms, const HealthCheck* health, EstimateRow* row);

// How far (relative) a radiometric estimate may depart from the apparent size's (the geometric
// estimate of the same frames) before `disagrees`: 10 x the geometric calibration's mean error,
// at least 0.5%. On the Table 3 validations the two agree within 0.1%; a model evaluated near a
// pole of its rational form, or features the scene spoilt, part them by percent.
double DisagreementTolerance(const CalibrationModel& model);
// Adds `disagrees` (with the relative departure) to `row` when both it and `size` are estimates
// and they differ by more than `tolerance` (relative to the size's).
void FlagDisagreement(const EstimateRow& size, double tolerance, EstimateRow* row);

// "+14%" / "-8%": a relative change as a flag's figure.
std::string PercentFigure(double fraction);

}  // namespace irdist
