#pragma once
// The image sensor after the EMVA 1288 linear model: photo-electrons (Poisson, with the mean the
// Scene gives plus dark current and a uniform background), clipped at the full well, read noise
// (Gaussian, electrons), system gain K to ADC counts, black level, optional compressive
// nonlinearity, rounding and clipping to the ADC range, then packed into Mono8/Mono12/Mono16.
//
// Speed: pixels inside the emitter's window are drawn exactly, pixel by pixel. Every other pixel
// has the same distribution (dark + background), so each frame draws 16384 exact samples of it
// and fills the rest of the frame by indexing that table with a fast generator; a full
// 1280x1024 frame takes a few milliseconds. Noise depends only on (seed, frame_index).
//
// Fixed-pattern noise (EMVA 1288, off unless prnu_percent/dsnu_e > 0): each pixel's photo-response
// is scaled by its own gain 1 + prnu_percent/100 x N(0,1) (PRNU) and its dark signal shifted by
// dsnu_e x N(0,1) electrons (DSNU). Both maps are drawn once, in the constructor, from the seed's
// own stream: the same camera (seed) shows the same pattern in every frame and every run.
//
// Inter-pixel crosstalk (crosstalk_sigma_px > 0): after the photons are counted, each
// photo-electron diffuses to a neighbouring pixel before it is collected (charge diffusion in the
// substrate). Modelled as a continuous-time random walk on the pixel lattice, each axis
// independently: the share of a pixel's charge that lands n pixels away along an axis is
// e^-t I_n(t), t = sigma^2 (I_n the modified Bessel function), whose variance is exactly sigma^2
// (CrosstalkKernel). Electrons that move independently of one another turn a Poisson field into a
// Poisson field (displacement theorem): the counts after diffusion are independent Poisson draws
// of the diffused mean. So the mean photo-electron image (after PRNU, which acts where the photon
// is absorbed) is diffused, then drawn; dark current and read noise are added after it.
//
// Defect pixels (options.defects, sim/defect_pixels.h; none by default): a hot pixel is drawn
// with its own extra dark charge (rate x exposure, Poisson) on top of what any pixel collects; a
// stuck pixel always reads its fixed level. Their values come from their own stream per
// (seed, frame, defect), so a region of interest never changes them.

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "sim/defect_pixels.h"
#include "sim/rig_physics.h"
#include "sim/scene.h"

namespace irdist::sim {

// Bits per pixel of the output format's container value range (Mono12 = 12 bits in 16).
int FormatBits(PixelFormat format);
// OpenCV type of an image in that format (CV_8UC1 or CV_16UC1).
int FormatCvType(PixelFormat format);

// The per-axis crosstalk kernel for sigma_px > 0, symmetric (w[-n] = w[n]), its weights w[n] for
// n = 0..reach renormalised to sum 1 over -reach..reach. The lattice walk: w[n] = e^-t I_n(t)
// (t = sigma_px^2), cut where the tail falls below 1e-9. The sampled Gaussian: w[n] =
// e^(-n^2 / (2 sigma_px^2)) for n <= 4 sigma_px. sigma_px = 0 gives {1}.
std::vector<double> CrosstalkKernel(double sigma_px, CrosstalkShape shape);

// The mean electron image after crosstalk: every pixel's electrons spread by the separable kernel.
// The window grows by the kernel's reach on every side, clipped to `sensor` (charge that diffuses
// off the sensor is lost); the total is conserved otherwise. sigma_px = 0 returns `electrons`.
SignalWindow DiffuseCharge(const SignalWindow& electrons, double sigma_px, CrosstalkShape shape,
                           const cv::Rect& sensor);
// The same with the sensor's own crosstalk (its sd and shape) over its whole area.
SignalWindow DiffuseCharge(const SignalWindow& electrons, const SensorOptions& sensor);

// The camera's pixel processing after the ADC (a LUT or gamma, sim/rig_physics.h's camera
// faults): each value v of `image` (in `format`'s range, full scale FS) becomes
// round(FS (v / FS)^gamma). gamma = 1 leaves it untouched.
void ApplyResponseCurve(double gamma, PixelFormat format, cv::Mat& image);

class Sensor {
 public:
  explicit Sensor(const SensorOptions& options);
  // The defects near the blob are placed around (near_x_px, near_y_px), full-sensor pixels (the
  // emitter's image centre; the one-argument form uses the sensor's centre).
  Sensor(const SensorOptions& options, double near_x_px, double near_y_px);

  const SensorOptions& options() const { return options_; }
  // The per-pixel gain (1 + PRNU) and dark offset (DSNU, electrons) at full-sensor pixel (x, y).
  double PixelGain(int x, int y) const;
  double PixelDarkOffsetE(int x, int y) const;
  // The hot and stuck pixels, fixed for the camera's life.
  const std::vector<DefectPixel>& defects() const { return defects_; }

  // Fills `out` (CV_8UC1 for Mono8, CV_16UC1 otherwise) with the frame seen through the region
  // whose top-left corner is `roi_origin` (full-sensor pixels; out's size is the region's size).
  // `signal` holds the mean signal electrons around the emitter; `black_offset_dn` is added to
  // the sensor's own black level (the camera's BlackLevel feature), in ADC counts.
  void Expose(const SignalWindow& signal, double exposure_s, std::uint64_t frame_index,
              PixelFormat format, cv::Point roi_origin, cv::Mat& out,
              double black_offset_dn = 0.0) const;
  // Convenience: the full sensor.
  cv::Mat Expose(const SignalWindow& signal, double exposure_s, std::uint64_t frame_index,
                 PixelFormat format) const;

  // Noise-free response: ADC counts (before packing) for a mean of `electrons` photo-electrons
  // plus the dark signal of `exposure_s`.
  double MeanAdc(double signal_electrons, double exposure_s, double black_offset_dn = 0.0) const;
  // Packs an ADC value into the output format's value range.
  std::uint16_t Pack(int adc, PixelFormat format) const;

 private:
  // The mean photo-electrons the pixels collect: `signal` times each pixel's PRNU gain, then
  // diffused by the crosstalk (DiffuseCharge).
  SignalWindow CollectedCharge(const SignalWindow& signal) const;
  // ADC value for `electrons` collected (clipped at the full well) plus read noise (electrons).
  int ToAdc(double electrons, double read_noise_e, double black_dn) const;
  // The table-drawn background of a frame (no DSNU).
  void FillBackground(double dark_e, std::uint64_t frame_index, PixelFormat format, double black_dn,
                      cv::Mat& out) const;
  // The exactly drawn pixels of `window` (full-sensor pixels, inside `roi`).
  void ExposeWindow(const SignalWindow& signal, cv::Rect window, double dark_e,
                    std::uint64_t frame_index, PixelFormat format, cv::Rect roi, double black_dn,
                    cv::Mat& out) const;
  // Draws the defect pixels inside `roi` over what ExposeWindow and the background drew.
  void ExposeDefects(const SignalWindow& collected, double exposure_s, double dark_e,
                     std::uint64_t frame_index, PixelFormat format, cv::Rect roi, double black_dn,
                     cv::Mat& out) const;
  // Draws the PRNU/DSNU maps (left empty when off).
  void DrawFixedPattern();
  // The table-drawn background, each pixel shifted by its DSNU (used when dsnu_e > 0).
  void FillWithDarkOffsets(double dark_e, std::uint64_t frame_index, PixelFormat format,
                           cv::Point roi_origin, double black_dn, cv::Mat& out) const;

  SensorOptions options_;
  cv::Mat1f gain_;       // full sensor; empty = 1 everywhere
  cv::Mat1f offset_e_;   // full sensor; empty = 0 everywhere
  std::vector<DefectPixel> defects_;
};

}  // namespace irdist::sim
