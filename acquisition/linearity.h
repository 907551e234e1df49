#pragma once
// The camera's response measured, not assumed (EMVA 1288's linearity error): a short exposure
// series on the scene's brightest window, a straight line fitted to the window's mean against the
// exposure, and the largest deviation from it in % of the series' range. A LUT, a gamma curve, a
// contrast feature or saturation bends the line; this catches every pixel-shaping feature whose
// name irdist does not know (acquisition/pixel_pipeline.h lists those it does).

#include <functional>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

namespace irdist {

class Camera;

struct LinearityPoint {
  double exposure_us = 0.0;
  double mean_dn = 0.0;  // the window's mean gray level
};

struct LinearityOptions {
  // The series spans these fractions of the range above the dark offset (EMVA 1288: 5%..95%).
  double low_fraction = 0.05;
  double high_fraction = 0.90;
  int points = 6;              // exposures in the series (5..8)
  int window_px = 16;          // side of the square window on the scene's brightest spot
  double limit_percent = 1.0;  // a linearity error above it fails
  // Points whose window mean lies above this fraction of the range are left out of the fit
  // (saturation, not the pipeline's shape).
  double saturation_fraction = 0.95;
  bool IsValid(std::string* why) const;
};

struct LinearityResult {
  bool measured = false;       // false: no light, too few points, or no frames (see `why`)
  std::string why;             // when not measured
  double dark_dn = 0.0;        // the window's mean at the dark frame
  double full_scale_dn = 0.0;  // the pixel format's largest value
  double slope_dn_per_us = 0.0;
  double intercept_dn = 0.0;   // the line at zero exposure
  double error_percent = 0.0;  // largest |deviation| from the line, % of the fitted range
  double limit_percent = 1.0;
  int points_used = 0;
  int points_saturated = 0;            // left out above saturation_fraction
  std::vector<LinearityPoint> points;  // every point taken, in exposure order
  bool Passed() const { return measured && error_percent <= limit_percent; }
  std::string BriefReport() const;
};

// Fits the line to `points` (those above `options.saturation_fraction` of the range left out):
// least squares of mean_dn on exposure_us; the error is the largest |residual| over the fitted
// range (the line's span between the smallest and largest exposure used), in percent.
// Not measured when fewer than 3 points remain or the range is under 5% of the full scale.
LinearityResult FitLinearity(double dark_dn, double full_scale_dn,
                             const std::vector<LinearityPoint>& points,
                             const LinearityOptions& options);

// A frame and the exposure the camera took it at (us): what it reads back, which may be the asked
// one rounded to the camera's step (a FLIR's ExposureTime is whole microseconds).
struct ExposedFrame {
  cv::Mat image;  // CV_16UC1
  double exposure_us = 0.0;
};
// A frame at an exposure (us), or nothing when none arrived.
using GrabAt = std::function<std::optional<ExposedFrame>(double exposure_us)>;

// The series on a camera: a dark frame (`grab_dark`, e.g. the shortest exposure or the source
// off), a probe at `probe_exposure_us` (shortened until the brightest window is unsaturated,
// lengthened until it is lit) that places the window, then options.points exposures from the low
// to the high fraction of the range by the probe's slope, each window's mean at the exposure the
// camera used (ExposedFrame); then the fit.
// Exposures stay inside [min_exposure_us, max_exposure_us]. A scene with no light says so.
LinearityResult MeasureLinearity(const GrabAt& grab,
                                 const std::function<std::optional<cv::Mat>()>& grab_dark,
                                 double probe_exposure_us, double min_exposure_us,
                                 double max_exposure_us, double full_scale_dn,
                                 const LinearityOptions& options);

// The series on a configured camera, each frame started by `fire` (a software or line trigger):
// the dark frame at `min_exposure_us`, the probe at `probe_exposure_us`; each exposure written,
// then read back as the one the frame was taken at (a camera may round it to its step, never a
// failure here); the stream started for it
// (and stopped after when it was not running), queued frames dropped before each, the exposure
// put back to the probe's after. Frames that do not arrive within the exposure plus 3 s end it as
// not measured.
LinearityResult MeasureCameraLinearity(Camera& camera, const std::function<void()>& fire,
                                       double probe_exposure_us, double min_exposure_us,
                                       double max_exposure_us, int bit_depth,
                                       const LinearityOptions& options);

}  // namespace irdist
