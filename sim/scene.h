#pragma once
// The scene: the IRED (a uniformly bright tilted disc with an emission pattern, a drive-current
// law and a thermal model) seen through the lens. It produces the mean number of signal
// photo-electrons per pixel: the disc's exact perspective image (the conic where rays through the
// pinhole meet the tilted disc) convolved with the optics' Gaussian PSF and integrated over each
// pixel, in closed form per strip of the image (no sampling of the sharp disc, so no aliasing;
// docs/virtual-rig.md). Noise, dark signal and quantisation are the Sensor's business. An occluder
// (virtual.scene.occluder) cuts the IRED's disc by a chord before the blur (EmitterDisc); the lab's
// other light sources are discs rendered the same way (RenderDisc, sim/lab_scene.h).
//
// Geometry: the camera's pinhole is the origin, the optical axis is +z, image x/y follow the
// sensor's columns/rows. The emitter's centre is at (offset_x_mm, offset_y_mm, slide_mm). Its
// emission axis is n = (sin(pan) cos(tilt), sin(tilt), -cos(pan) cos(tilt)), so at pan = tilt = 0
// it points at the camera and cos(theta) = cos(pan) cos(tilt) (sim/world.h).

#include <array>
#include <vector>

#include <opencv2/core.hpp>

#include "sim/lens_psf.h"
#include "sim/rig_physics.h"
#include "sim/world.h"

namespace irdist::sim {

struct ImageStrip;  // one horizontal strip of the disc's image (sim/disc_image.h)

// A uniformly bright circular disc in the camera's frame (mm): the IRED, its mirror image in the
// table, a second source (sim/lab_scene.h). Its image is rendered exactly as the IRED's is.
struct DiscSource {
  std::array<double, 3> center_mm{};
  std::array<double, 3> axis{};  // unit normal on the emitting side (towards the camera to be seen)
  double diameter_mm = 0.0;
  double intensity_mw_sr = 0.0;  // radiant intensity along the axis
  // true: a uniform (Lambertian) radiance I / area in every direction; false: the IRED's emission
  // pattern, I Pattern(a) / (area cos a) at emission angle a.
  bool lambertian = false;
  // An opaque straight edge in the disc's plane: the part where (p - centre) . cut_direction >
  // cut_offset_mm is covered (cut_direction a unit vector in the plane). Off when `cut` is false.
  bool cut = false;
  std::array<double, 3> cut_direction{};
  double cut_offset_mm = 0.0;
};

// Mean signal photo-electrons per pixel over a window of the full sensor (no dark signal).
struct SignalWindow {
  cv::Rect rect;     // in full-sensor pixel coordinates (may be empty)
  cv::Mat1f electrons;  // rect.height x rect.width
};

// Geometry of the emitter's image, for reports and tests.
struct EmitterImage {
  double center_x_px = 0.0;  // projected centre of the disc (full-sensor pixels)
  double center_y_px = 0.0;
  double major_px = 0.0;     // full axes of the projected ellipse (before blur)
  double minor_px = 0.0;
  double theta_deg = 0.0;    // angle between emission axis and the line to the camera
};

// Below this PSF sd along y (px) the disc's strips are split at the pixel rows' borders
// (Scene::DiscStrips); above it the PSF spreads each strip over rows smoothly (at 0.2 px the
// unsplit strips already give a face-on disc's x and y variances within 1e-5 of each other).
constexpr double kRowSplitSdPx = 0.25;

class Scene {
 public:
  explicit Scene(const RigPhysics& physics);

  const RigPhysics& physics() const { return physics_; }

  // Junction temperature rise (K) above ambient at simulated time t_s, integrating the
  // first-order thermal model over the piecewise-constant current history.
  double JunctionRiseK(const std::vector<CurrentStep>& history, double t_s) const;
  // On-axis radiant intensity (mW/sr) at bias current i and a junction rise dT.
  double OnAxisIntensityMwSr(double bias_ma, double junction_rise_k) const;
  // Relative emission pattern rho(angle), 1 on axis.
  double Pattern(double angle_rad) const;

  EmitterImage Project(const PoseState& pose) const;

  // Thin-lens circle of confusion (diameter, px on the sensor) of an object at `distance_mm`
  // along the optical axis: (f / N) f |d - s| / (d (s - f)) / pitch, s = optics.focus_mm; 0 when
  // focus_mm is 0 (no defocus).
  double CircleOfConfusionPx(double distance_mm) const;
  // Gaussian sigma (px) of the total blur at `distance_mm`: the lens PSF (an elliptical one's
  // mean variance per axis) and the defocus disc (a uniform disc of diameter c has per-axis
  // variance c^2 / 16), variances added; the halo left out.
  double BlurSigmaPx(double distance_mm) const;

  // The lens's PSF at `distance_mm` (sim/lens_psf.h): the in-focus PSF (round or elliptical), the
  // defocus (a Gaussian or the geometric disc, optics.defocus_disc) and the halo.
  LensPsf PsfAt(double distance_mm) const;

  // Mean signal electrons per pixel for an exposure of `exposure_s` seconds at on-axis intensity
  // `intensity_mw_sr`, over a window around the emitter's image (clipped to the sensor).
  SignalWindow RenderSignal(const PoseState& pose, double intensity_mw_sr,
                            double exposure_s) const;

  // The IRED's disc at the pose: centre, emission axis, intensity and the occluder's cut
  // (virtual.scene.occluder, which moves with the emitter).
  DiscSource EmitterDisc(const PoseState& pose, double intensity_mw_sr) const;
  // Mean signal electrons of any disc over a window around its image (its blur that of its
  // distance along the optical axis), clipped to the sensor.
  SignalWindow RenderDisc(const DiscSource& disc, double exposure_s) const;

  // Photo-electrons per second per pixel per unit scene radiance (W m^-2 sr^-1) on the axis.
  double ElectronsPerRadianceSecond() const { return electrons_per_radiance_s_; }

 private:
  // The window around the emitter's image holding its PSF's reach, clipped to the sensor.
  cv::Rect SignalRect(const EmitterImage& image, const LensPsf& psf) const;
  // The disc's image as Chebyshev-spaced horizontal strips with their chords and radiance (W m^-2
  // sr^-1, vignetting included); empty when the disc is not an ellipse in view. A cut disc's
  // strips are spaced so over each range of rows where its visible chord is smooth. Behind a PSF
  // whose sd along y is below kRowSplitSdPx, each strip's light falls into one pixel row whole,
  // so the ranges are also split where the pixels' sensitive heights begin and end (each part
  // then integrated on its own: the strips alone quantise y, and a sharp disc read 2% wider along
  // x than along y).
  std::vector<ImageStrip> DiscStrips(const DiscSource& disc, const LensPsf& psf) const;

  RigPhysics physics_;
  double electrons_per_radiance_s_ = 0.0;
};

}  // namespace irdist::sim
