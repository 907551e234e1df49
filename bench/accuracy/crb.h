#pragma once
// Cramer-Rao bound on the distance d and the orientation theta of the IRED from the virtual
// rig's noise-free rendered signal and the sensor's EMVA 1288 noise model (shot noise of the
// expected electrons, dark signal, read noise, quantisation), for a set of frames that share the
// unknowns (ln I0, theta, blob position x/y, d). The Fisher information is the sum over pixels and
// frames of (d mu / d p_i)(d mu / d p_j) / var, the derivatives of the expected image by central
// finite differences of the renderer.

#include <string>
#include <vector>

#include "sim/rig_physics.h"

namespace irdist {

struct CrbConditions {
  double d_mm = 2700.0;
  double theta_deg = 0.0;
  double bias_ma = 500.0;
  double junction_rise_k = 0.0;  // IRED junction rise above ambient for every frame
  std::vector<double> exposures_ms;  // every frame of the set (reference and measurements)
};

struct CrbResult {
  bool valid = false;
  double d_sd_mm = 0.0;      // bound (standard deviation) on d, all other unknowns free
  double theta_sd_deg = 0.0;  // bound on theta; < 0 when theta is not identifiable to first
                              // order (theta = 0: the image is even in theta)
  double d_sd_known_theta_mm = 0.0;  // bound on d with theta known
  double signal_e = 0.0;     // total signal electrons over the frames
  double peak_e = 0.0;       // brightest pixel's expected electrons (longest frame)
  std::string BriefReport() const;
};

// The bound for `conditions` on the rig `physics` (the emitter on the optical axis; its position
// is perturbed through the emitter's offset). The renderer's sub-sampling is raised so that the
// finite differences are smooth.
CrbResult ComputeCrb(const sim::RigPhysics& physics, const CrbConditions& conditions);

}  // namespace irdist
