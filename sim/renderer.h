#pragma once
// One frame of the virtual camera: the Scene's signal for the state of the world during the
// exposure (the IRED, and the lab's other light when virtual.scene: turns it on: sim/lab_scene.h),
// exposed on the Sensor. Also the scene's ground truth for a pose (blob size, peak gray
// level) for reports. Thread-safe (const) once constructed.

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "sim/lab_scene.h"
#include "sim/rig_physics.h"
#include "sim/scene.h"
#include "sim/sensor.h"
#include "sim/world.h"

namespace irdist::sim {

// The physical state seen by one exposure.
struct FrameConditions {
  PoseState pose_start;        // state when the exposure starts
  PoseState pose_end;          // state when it ends (differs while an axis moves)
  // A moving exposure's sub-steps: the states at the middles of equal parts of the exposure,
  // each exposed for exposure_s / size (empty: the start and end states above).
  std::vector<PoseState> sub_steps;
  double exposure_s = 0.008;
  double junction_rise_k = 0.0;  // IRED junction temperature above ambient, mid-exposure
  double black_offset_dn = 0.0;  // camera BlackLevel feature, ADC counts
};

// What the scene looks like for one pose, current and exposure, without noise.
struct GroundTruth {
  double theta_deg = 0.0;
  double major_px = 0.0;           // geometric ellipse axes of the emitter's image
  double minor_px = 0.0;
  double blur_sigma_px = 0.0;      // total Gaussian blur (lens PSF and defocus) at this distance
  double coc_px = 0.0;             // thin-lens circle of confusion (diameter) at this distance
  double width_px = 0.0;           // 2 * sqrt(second moment) along x and y after blur,
  double height_px = 0.0;          //   i.e. the blob's intensity-weighted size
  double intensity_mw_sr = 0.0;    // on-axis radiant intensity
  double signal_e = 0.0;           // total signal photo-electrons
  double peak_signal_e = 0.0;      // brightest pixel's mean signal electrons
  double peak_adc = 0.0;           // brightest pixel's mean ADC value incl. dark and black level
  double peak_gray = 0.0;          // the same in the output format
  bool saturated = false;          // peak reaches full well or ADC maximum
  std::string BriefReport() const;
};

class Renderer {
 public:
  explicit Renderer(const RigPhysics& physics);

  const Scene& scene() const { return scene_; }
  const Sensor& sensor() const { return sensor_; }

  const LabScene& lab() const { return lab_; }

  // Mean signal electrons for the conditions (the sum over a moving exposure's sub-steps; else
  // averaging the start and end poses, and the intensity at the bias currents of both): the
  // IRED, its reflection and the
  // second source (ambient light, which covers the sensor, is added by Render for its region).
  SignalWindow Signal(const FrameConditions& conditions) const;

  // Renders the region with top-left `roi_origin` and out's size into `out` (type from format).
  void Render(const FrameConditions& conditions, std::uint64_t frame_index, PixelFormat format,
              cv::Point roi_origin, cv::Mat& out) const;
  // The full sensor.
  cv::Mat Render(const FrameConditions& conditions, std::uint64_t frame_index,
                 PixelFormat format) const;

  // Noise-free description of a static pose at `bias_ma` (junction at `junction_rise_k`): the
  // IRED's image alone (the occluder's cut included; no reflection, second source or ambient).
  GroundTruth Describe(const PoseState& pose, double exposure_s, PixelFormat format,
                       double junction_rise_k = 0.0) const;

 private:
  // The IRED at one pose and intensity for `exposure_s`, with its reflection.
  SignalWindow EmitterSignal(const PoseState& pose, double intensity_mw_sr,
                             double exposure_s) const;

  Scene scene_;
  LabScene lab_;
  Sensor sensor_;
  int ambient_margin_px_ = 0;  // ambient light drawn this far around the region (crosstalk)
};

// Conditions for a static pose (start = end) and a cold emitter: a helper for tests and reports.
FrameConditions StaticConditions(double slide_mm, double pan_deg, double tilt_deg, double bias_ma,
                                 double exposure_s);

}  // namespace irdist::sim
