#pragma once
// The one-frame Cramer-Rao bound on d for the tracking tests: the rig's physics
// (sim/rig_physics.h), one frame at the pose and exposure, every unknown free
// (app/processing/crb.h ComputeCrb).

#include <cmath>
#include <string>

#include "app/processing/crb.h"
#include "sim/rig_physics.h"

namespace irdist {
namespace testing {

// The bound (mm) for `physics` at d_mm, pan_deg, one exposure_ms frame at bias_ma; NaN when it
// cannot be formed.
inline double OneFrameBoundMm(const sim::RigPhysics& physics, double d_mm, double pan_deg,
                              double exposure_ms, double bias_ma) {
  const CrbResult r = ComputeCrb(
      physics, {d_mm, pan_deg, bias_ma, SteadyJunctionRiseK(physics, bias_ma), {exposure_ms}});
  return r.valid ? r.d_sd_mm : NAN;
}

}  // namespace testing
}  // namespace irdist
