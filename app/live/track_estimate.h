#pragma once
// One frame's estimate for `irdist measure --track` (docs/measure.md "Tracking"): the blob's
// apparent size through the calibration's geometric model (the size the default bracket estimate
// leans on: docs/estimator.md), theta from the fitted disc's axes with the calibrated blur
// removed, the 3D position along the blob's ray with the rig's intrinsics, the frame's scene
// flags, calibrated ranges and calibration health: the fields of measure's JSON for one frame.

#include <cstdint>
#include <vector>

#include "app/live/measure_output.h"
#include "app/processing/position.h"
#include "estimator/features.h"
#include "estimator/fit.h"

namespace irdist {

// The per-frame distance's standard error (mm) at d_mm for a frame exposed `exposure_ms`: the
// calibrated size noise of one measurement frame (GeometricModel::NoiseRel, fitted on the
// calibration's measurement frames) where the model has it, else the geometric fit's mean
// relative error; scaled by sqrt(t_cal / exposure_ms), t_cal the calibration's mean measurement
// exposure (a size's noise falls as 1 / sqrt(signal), and the signal is proportional to the
// exposure on a linear camera). NaN when the model has neither.
double FrameDistanceSeMm(const CalibrationModel& model, double d_mm, double exposure_ms);

// The estimate of one frame taken at `exposure_ms`, from its features (FrameFeatures with the
// model's blob fit, in the frame's own pixels). `frame` numbers the sample
// (MeasureSample::bracket). A frame without a usable blob gives a sample without an estimate
// (have_estimate true, ok false), never an exception. `health_frames`: the frames whose own
// blurs the calibration health pools (the track's last frames); empty: the frame itself.
MeasureSample EstimateFrame(const Features& features, double exposure_ms,
                            const CalibrationModel& model, const CameraGeometry& geometry,
                            std::int64_t frame,
                            const std::vector<const Features*>& health_frames = {});

}  // namespace irdist
