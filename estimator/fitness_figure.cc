// The fit's fitness figure (fitness_figure.h): its probable cause and its text.
#include "estimator/fitness_figure.h"

#include <algorithm>
#include <sstream>

namespace irdist {
namespace {

// A pose whose own scatter exceeds its distance's this many times: its frames disagree among
// themselves (for 3 frames' 2 degrees of freedom, chance gives this about once in 20000 poses).
constexpr double kMovingScatterRatio = 10.0;

std::string Number(double value, int precision) {
  std::ostringstream s;
  s.precision(precision);
  s << value;
  return s.str();
}

}  // namespace

std::string FitnessCause(const CalibrationFitness& f) {
  for (const PoseFitness& p : f.worst) {
    if (p.chi2 > f.pose_limit && p.scatter_ratio > kMovingScatterRatio) {
      return "the IRED or the stage moved during a bracket: the frames of " + PoseText(p.pose) +
             " disagree among themselves (" + Number(p.scatter_ratio, 3) +
             "x the scatter of its distance's other poses); check the mount, the stage's "
             "settling and the recipe's settle times, then calibrate again";
    }
  }
  if (f.poses_over >= std::max(3, f.poses / 4)) {
    return "an optic outside the model's family: " + std::to_string(f.poses_over) + " of " +
           std::to_string(f.poses) + " poses miss, steadily across the grid (an astigmatic, "
           "defocused or haloed PSF, or a shape the disc-plus-blur size does not describe, such "
           "as a cable over the disc that moves with the IRED; a 'minor' residual at theta 0 is "
           "the PSF's own shape); the model reads these poses wrong by about the residuals named";
  }
  return "a scene fault at a few poses (" + std::to_string(f.poses_over) + " of " +
         std::to_string(f.poses) + " miss, the rest fit within their noise): a reflection, a "
         "second source or an occluder there, or the stage off its recorded position; look at "
         "the frames of the poses named (irdist check RECORDING shows each bracket's scene)";
}

std::string PoseText(const FitnessPose& pose) {
  return "slide " + Number(pose.slide_mm, 6) + " mm, pan " + Number(pose.pan_deg, 4) +
         " deg, tilt " + Number(pose.tilt_deg, 4) + " deg, " + Number(pose.bias_ma, 5) + " mA";
}

std::string CalibrationFitness::BriefReport() const {
  if (!assessed) return "fitness: not assessed (fewer than 2 poses with frames to compare)";
  std::ostringstream s;
  s << "fitness: reduced chi-square " << Number(reduced_chi2, 4) << " over " << dof
    << " degrees of freedom (limit " << Number(limit, 4) << " at tail probability "
    << tail_probability << "; model-error floors " << Number(100.0 * size_floor, 3)
    << "% size, " << Number(100.0 * difference_floor, 3) << "% dE/dSigma); " << poses_over
    << " of " << poses << " poses beyond " << Number(pose_limit, 4) << ": "
    << (passed ? "passed" : "FAILED");
  for (const PoseFitness& p : worst) {
    s << "\n    " << PoseText(p.pose) << ": chi2 " << Number(p.chi2, 4) << " (" << p.channels
      << " channels), worst " << p.worst_channel << " "
      << (p.worst_residual_percent > 0.0 ? "+" : "") << Number(p.worst_residual_percent, 3)
      << "%, scatter "
      << Number(p.scatter_ratio, 3) << "x its distance's";
  }
  return s.str();
}

}  // namespace irdist
