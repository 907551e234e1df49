#pragma once
// The flags of a bracket's estimates (docs/reports.md, "Flags"): every cause that makes an
// estimate suspect, named with its figure, and the notes of what it was measured through, the
// same for validate, playback, measure and the Python module (EstimateRecordedBracket sets them).
// A bracket's frames give the scene's flags (the scene pass of estimator/scene.h: defect pixels,
// other blobs, a second source, an occluded disc; saturation, the window's border); each row adds
// its own ranges, motion and calibration health.

#include <string>
#include <vector>

#include "app/reports/estimates_csv.h"
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

// The scene's and the frames' flags of a bracket (every frame given: references and measurements),
// the same for each of its rows: notes (defect_pixels, other_blobs) and suspects (no_blob,
// saturated, touches_border, clipped, second_source, occluded), each with the worst figure over
// the frames.
std::vector<EstimateFlag> FrameFlags(const std::vector<const Features*>& frames);

// A row's range, motion and health flags on top of `frame_flags`: `outside` with its ranges,
// except a `t_meas` within kExposureExtrapolation of the calibrated exposures (`t_ms`, the row's
// measurement exposures), which becomes the note `t_meas_extrapolated` and leaves the row's
// outside list and outside_range; `moving` with the spread; `blur_larger`/`blur_smaller` with the
// blur's change when `health` is given and flagged; `no_estimate` on a row without an estimate.
void FlagRow(const std::vector<EstimateFlag>& frame_flags, const CalibratedRanges& ranges,
             const std::vector<double>& t_ms, const HealthCheck* health, EstimateRow* row);

// "+14%" / "-8%": a relative change as a flag's figure.
std::string PercentFigure(double fraction);

}  // namespace irdist
