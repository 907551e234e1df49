#pragma once
// The Cramer-Rao bound of a recipe's poses on the VIRTUAL rig, and the bound beside the measured
// figures of a validation (summary.yaml's `crb:` blocks, the report's header).
//
// What the bound knows: the virtual rig's physics (the rig file's `virtual:` section, as the
// recording stored it in rig.yaml): the renderer's expected image of the IRED (its emitter, lens,
// defocus, pixel integration) and the sensor's EMVA 1288 temporal noise (shot noise of signal and
// dark electrons, read noise, quantisation). That is the truth the frames were drawn from, so the
// bound is the limit of ANY unbiased estimator on these frames, not of our model of them. A
// hardware rig has no such physics (the calibration knows the blob's size and blur, not the
// sensor's gain, read noise or the emitter's radiance): there the bound is not computed and the
// summary says why. The fixed-pattern noise (PRNU/DSNU) is not in the bound (it is the same in
// every repetition, a bias, not a dispersion). The IRED's junction is taken at its steady-state
// rise for the pose's current (the validation's self-heating history is not replayed).
//
// Unknowns shared by the frames of one bracket: ln I0, theta, the blob's x and y, d
// (estimator/crb.h); the expected image and its derivatives come from the renderer by central
// differences (one-sided in theta at theta = 0, where theta is not identifiable to first order).

#include <map>
#include <string>
#include <vector>

#include "app/processing/validation_summary.h"
#include "estimator/crb.h"
#include "sim/rig_physics.h"

namespace irdist {

struct CrbConditions {
  double d_mm = 2700.0;
  double theta_deg = 0.0;  // pan angle, tilt 0
  double bias_ma = 500.0;
  double junction_rise_k = 0.0;      // IRED junction rise above ambient for every frame
  std::vector<double> exposures_ms;  // every frame of the set (reference and measurements)
};

// The steady-state junction rise (K) of the rig's IRED at bias_ma: R_th * i * V_f.
double SteadyJunctionRiseK(const sim::RigPhysics& physics, double bias_ma);

// The bound for `conditions` on the rig `physics`; the emitter at the rig's own lateral offset.
CrbResult ComputeCrb(const sim::RigPhysics& physics, const CrbConditions& conditions);

// What a recording offers the bound: the virtual rig's physics and the exposures of a bracket.
struct RecordingCrbSource {
  bool available = false;
  std::string why;  // when not available: what is missing
  sim::RigPhysics physics;
  std::vector<double> exposures_ms;  // reference first, then the measurement exposures
  std::string identity;              // the rig text and exposures (the bound cache's key)
};
// Reads recording.yaml, rig.yaml and frames.csv of `recording_dir`. Never throws for a recording
// whose rig is not virtual or cannot be read: `why` says so.
RecordingCrbSource CrbSourceOfRecording(const std::string& recording_dir);

// The bound beside each method's figures of a validation whose recording is context["recording"]
// (no entry in the map when there is none; an entry with `available` false and `why` when the
// rig is not virtual). Bounds are cached per rig text, exposures and condition, so the summary
// and the report compute each once per process.
std::map<std::string, CrbFigures> ValidationCrb(const std::map<std::string, std::string>& context,
                                                const ValidationSummary& summary);

// The same from a source already read (tests, the accuracy study).
CrbFigures MethodCrb(const RecordingCrbSource& source, const MethodSummary& method);

}  // namespace irdist
