#include "app/runs/linearity_check.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "acquisition/aravis_camera.h"
#include "base/check.h"
#include "base/regular_file.h"
#include "base/safe_file.h"

namespace irdist {

std::string LinearityYaml(const LinearityResult& r) {
  std::ostringstream out;
  out.precision(8);
  out << "# The camera's linearity at the calibration's first pose (EMVA 1288 linearity error).\n"
      << "measured: " << (r.measured ? "true" : "false") << "\n";
  if (!r.measured) out << "why: \"" << r.why << "\"\n";
  out << "linearity_error_percent: " << r.error_percent << "\n"
      << "limit_percent: " << r.limit_percent << "\n"
      << "passed: " << (r.Passed() ? "true" : "false") << "\n"
      << "dark_offset_dn: " << r.dark_dn << "\n"
      << "full_scale_dn: " << r.full_scale_dn << "\n"
      << "slope_dn_per_us: " << r.slope_dn_per_us << "\n"
      << "intercept_dn: " << r.intercept_dn << "\n"
      << "points_used: " << r.points_used << "\n"
      << "points_saturated: " << r.points_saturated << "\n"
      << "points:  # exposure_us, the window's mean (DN)\n";
  for (const LinearityPoint& p : r.points) {
    out << "  - [" << p.exposure_us << ", " << p.mean_dn << "]\n";
  }
  return out.str();
}

bool NeedsFirstPoseLinearity(const std::string& recording_dir, bool resume) {
  if (!resume) return true;
  std::string text, why;
  if (!ReadRegularFile(recording_dir + "/linearity.yaml", 1 << 20, &text, &why)) return true;
  return text.find("\npassed: true\n") == std::string::npos;
}

bool FirstPoseLinearityOptions::IsValid(std::string* why) const {
  std::string reason;
  if (recording_dir.empty()) {
    reason = "recording_dir is empty";
  } else if (!(probe_exposure_us > 0.0) || !std::isfinite(probe_exposure_us)) {
    reason = "probe_exposure_us not a finite number > 0";
  } else if (bit_depth < 8 || bit_depth > 16) {
    reason = "bit_depth not in [8, 16]";
  }
  if (why != nullptr) *why = reason;
  return reason.empty();
}

LinearityResult CheckFirstPoseLinearity(AravisCamera& camera, const std::function<void()>& fire,
                                        const FirstPoseLinearityOptions& options,
                                        std::ostream& out) {
  std::string invalid;
  IRDIST_CHECK(options.IsValid(&invalid), "FirstPoseLinearityOptions: " + invalid);
  const auto [min_us, max_us] = camera.ExposureBoundsUs();
  const LinearityResult result = MeasureCameraLinearity(
      camera, fire, options.probe_exposure_us, min_us,
      std::min(max_us, 20.0 * options.probe_exposure_us), options.bit_depth, LinearityOptions{});
  const std::string path = options.recording_dir + "/linearity.yaml";
  std::string why;
  if (!WriteFileAtomically(path, LinearityYaml(result), 0644, &why)) {
    throw CameraError("could not write " + path + ": " + why +
                      ". Free space or fix the folder's "
                      "permissions, then resume the run.");
  }
  out << "Camera linearity at the first pose: " << result.BriefReport() << " (" << path << ")\n";
  if (result.measured && !result.Passed() && !options.allow_nonlinear) {
    throw CameraError(
        "the camera's response is not linear at the first pose: " + result.BriefReport() +
        ". Probable causes: a LUT, a gamma curve, a contrast "
        "feature or saturation; switch it off (irdist camera-test lists the pixel "
        "features it knows), or pass --allow-nonlinear to calibrate anyway.");
  }
  return result;
}

}  // namespace irdist
