#pragma once
// The calibrated blur of the blob: how the blob's measured blur variance (Features::blur_var_px2)
// depends on the distance, fitted from the calibration frames (estimator/fit.h stores it in the
// CalibrationModel) and checked against in measurement (estimator/health.h). docs/estimator.md.

#include <algorithm>
#include <vector>

namespace irdist {

// The pixel's own area, part of every blur variance measured on pixels (per axis, px^2): the
// variance of a uniform over one pixel.
constexpr double kPixelAreaVarPx2 = 1.0 / 12.0;

// The optics' variance keeps at least this (0.02 px of sd): the crosstalk cannot be the whole blur
// (the blob fit's edge model divides by the optics' sd). At 0.1 px, a sensor with all of its blur
// after the pixels read its sizes 0.03-0.04% off with the edge's phase through that floor alone.
constexpr double kMinOpticsVarPx2 = 0.0004;
// The least total blur the blob fit takes: the pixel's area and the optics' floor.
constexpr double kLeastBlurVarPx2 = kPixelAreaVarPx2 + kMinOpticsVarPx2;

// The blob fit's edge correction's table (BlurCalibration::edge_correction): its knots every
// kEdgeCorrectionStepPx over [-kEdgeCorrectionHalfWidthPx, +kEdgeCorrectionHalfWidthPx] of a
// pixel's offset from the edge (blob_pixel_model.h EdgeOffsetPx), linear between them, 0 beyond
// (the table tapers to 0 at its ends: the model stays continuous).
constexpr double kEdgeCorrectionHalfWidthPx = 5.0;
constexpr double kEdgeCorrectionStepPx = 0.1;
constexpr int kEdgeCorrectionKnots = 101;
static_assert((kEdgeCorrectionKnots - 1) * kEdgeCorrectionStepPx == 2 * kEdgeCorrectionHalfWidthPx,
              "the knots span the table");

// The blob fit's blur offset o0 + o1 u + o2 u^2 at u = 1000 / d_mm (px^2): BlurCalibration's
// fit_offset_*, blob_fit.h BlurSplit's blur_offset_*, blur_level.h FitOffsetCurve's fit.
inline double OffsetCurvePx2(double o0, double o1, double o2, double u) {
  return o0 + (o1 + o2 * u) * u;
}

// The calibrated blur: blur_var(u) = c0 + c1 u + c2 u^2, u = 1000 mm / d (the thin lens's defocus
// variance is quadratic in u), and the per-frame sd of the measurement around it,
// sd(d) = noise_at_1m (d / 1000 mm)^noise_exponent, both from the calibration frames.
struct BlurCalibration {
  double c0_px2 = 0.0, c1_px2 = 0.0, c2_px2 = 0.0;
  double noise_at_1m_px2 = 0.0;
  double noise_exponent = 0.0;
  int frames = 0;
  // The part of the blur after the pixels sample the image (inter-pixel crosstalk), px^2, fitted
  // from calibration frames by the blob fit (blob_fit.h FitBlurSplit); 0 = all of it before
  // (optics), as in model files before it.
  double crosstalk_var_px2 = 0.0;
  // The crosstalk kernel's shape: the share of its variance spread as a lattice random walk, the
  // rest as a sampled Gaussian (blob_fit.h Crosstalk). 0 in files before it.
  double crosstalk_lattice_share = 0.0;
  // The optics' line spread's excess kurtosis (blob_fit.h Crosstalk), fitted with the split: the
  // blob fit's edge beyond a Gaussian's. 0 in files before it (a Gaussian).
  double optics_excess = 0.0;
  // The blob fit's own correction to the cumulants' blur, fit_offset_px2 + fit_offset_u_px2 u +
  // fit_offset_u2_px2 u^2, u = 1000 / d_mm (px^2): the total blur that fits the calibration frames
  // best with the split above (blob_fit.h FitBlurSplit). The cumulants of a sharp edge read a few
  // 0.01 px^2 off, and the fit's axis ratio is that sensitive to it. 0 in files before it (the u^2
  // term: before 2026-12-07). BlurVarPx2 and health keep the cumulants' own blur.
  double fit_offset_px2 = 0.0;
  double fit_offset_u_px2 = 0.0;
  double fit_offset_u2_px2 = 0.0;
  // The optics' PSF anisotropy (an astigmatic lens: an elliptical PSF), the traceless part of its
  // covariance, constant in pixels: ((Sxx - Syy) / 2, Sxy) px^2 in the sensor's axes, fitted from
  // the face-on calibration frames (estimator/psf_anisotropy.h). The blob fit blurs each edge
  // point by n^T S n for its normal n; the moments lose it. 0 in files before it (a round PSF).
  double psf_aniso_c_px2 = 0.0;
  double psf_aniso_s_px2 = 0.0;
  // The blob fit's edge correction (estimator/edge_correction.h): the pixel's mean at each of
  // the kEdgeCorrectionKnots offsets from the edge, learned from the calibration frames'
  // residuals where they show the lens's edge is not the fit's. Empty: none (files before it,
  // and every lens whose residuals are within their noise).
  std::vector<double> edge_correction;
  // The blur the blob fit is given at d_mm: BlurVarPx2 plus the fit's offset.
  double FitBlurVarPx2(double d_mm) const {
    return BlurVarPx2(d_mm) +
           OffsetCurvePx2(fit_offset_px2, fit_offset_u_px2, fit_offset_u2_px2, 1000.0 / d_mm);
  }
  // The optics' blur (FitBlurVarPx2 less the pixel's area) at the sharper end of [d_min_mm,
  // d_max_mm]: what a lens's PSF anisotropy stays below (psf_anisotropy.h PsfAnisotropyPossible).
  double LeastOpticsVarPx2(double d_min_mm, double d_max_mm) const {
    return std::min(FitBlurVarPx2(d_min_mm), FitBlurVarPx2(d_max_mm)) - kPixelAreaVarPx2;
  }
  bool fitted() const { return noise_at_1m_px2 > 0.0; }
  double BlurVarPx2(double d_mm) const;
  double NoisePx2(double d_mm) const;
};

// One calibration frame's measured blur at its true distance.
struct BlurPoint {
  double d_mm = 0.0;
  double blur_var_px2 = 0.0;
};

// The residuals of a fit at one calibrated distance, for a noise law sd(d).
struct NoiseGroup {
  double ln_d_1m = 0.0;  // ln(d / 1000 mm)
  double sum_r2 = 0.0;   // sum of the squared residuals there
  int count = 0;
};

// A noise law sd(d) = at_1m (d / 1000 mm)^exponent: ln rms = ln at_1m + exponent ln(d / 1000 mm)
// by least squares over the groups' rms (groups of >= 3 with residuals), weighted by their
// sizes. With one such group, exponent 0 and at_1m its rms. False (nothing set) without one.
bool FitNoiseLaw(const std::vector<NoiseGroup>& groups, double* at_1m, double* exponent);

// Minimum number of frames FitBlurCalibration needs.
constexpr int kMinBlurCalibrationFrames = 12;

// Fits the calibrated blur to the frames with a measured blur (the usable measurement frames of
// the calibration); not fitted (noise 0) with fewer than kMinBlurCalibrationFrames points.
BlurCalibration FitBlurCalibration(const std::vector<BlurPoint>& points);

}  // namespace irdist
