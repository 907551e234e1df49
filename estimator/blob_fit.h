#pragma once
// A likelihood fit of the IRED's blob with the CALIBRATED blur: the blob is a uniformly
// bright elliptical disc {p : (p - c)^T P (p - c) <= 1}, blurred by a Gaussian whose variance is
// the calibration's blur b(u) at the frame's distance less the pixel area (1/12 px^2; the pixel's
// own spread is folded into the edge's blur, one evaluation per pixel), on the frame's background.
// Unknowns: centre, P (3), amplitude, background; the Jacobian is analytic, summed into the
// normal equations of a Levenberg-Marquardt (estimator/normal_lm.h; about 0.4 ms for a 7 px disc,
// bench_estimator). Two passes: the read noise's weights, then weights of the first pass's own
// shape, var = read (1 + signal / (0.1 amplitude)): shot noise over a floor, the same whatever the
// frame's amplitude and noise, so that the size is one (noisy or noise free, bright or dim) where
// the lens is not the model's. The errors are the solution's under the frame's own noise (EMVA
// 1288: var = read + k x signal, read measured on the frame's background and k regressed from the
// residuals; a sandwich covariance). Second moments weight the noise in the blob's wings by r^2;
// this fit weights each pixel near its information, and fixing the blur removes the
// size-blur correlation that a free-blur fit (EllipseMethod::kModelFit) pays for.
//
// The result replaces the blob's second-moment variances by the fitted disc's (A^2/4, B^2/4 for
// semi-axes A, B; the larger taken without the noise bias a near-round blob's larger eigenvalue
// has) plus the same calibrated blur b(u): quantities with the moments' expectation,
// so the calibrated geometric model, theta (kCalibratedBlur) and the fused solve use them as they
// are. The distance for b(u) is the moments' geometric distance (b(u) changes slowly with d).

#include <algorithm>
#include <cstddef>
#include <limits>
#include <memory>
#include <opencv2/core.hpp>
#include <utility>
#include <vector>

#include "base/bounds.h"
#include "estimator/blur_model.h"  // kPixelAreaVarPx2, kMinOpticsVarPx2, OffsetCurvePx2
#include "estimator/features.h"
#include "estimator/fit.h"
#include "estimator/psf_anisotropy.h"

namespace irdist {

// The blur after the pixels sample the image (inter-pixel crosstalk): its variance (px^2 on the
// grid) and the share of it spread as a lattice random walk (charge hopping to neighbours,
// e^-t I_n(t)); the rest as a sampled Gaussian (a blur of the sampled image). Implicit from a
// variance: a sampled Gaussian. With it, the one shape parameter of the blur before the pixels:
// the optics' line spread's excess kurtosis as a Gram-Charlier term (blob_pixel_model.h; 0 a
// Gaussian; a defocus disc's flat top < 0, an Airy pattern's or a halo's peaked core and
// tails > 0), fitted with the split (FitBlurSplit).
constexpr double kMinOpticsExcess = bounds::kOpticsExcess.min;  // Gram-Charlier's reach
constexpr double kMaxOpticsExcess = bounds::kOpticsExcess.max;
// And the edge's correction learned from the calibration frames' residuals
// (estimator/edge_correction.h; null: none), which every Crosstalk made from another carries on.
struct Crosstalk {
  Crosstalk(double var = 0.0, double share = 0.0, double excess = 0.0,  // NOLINT
            std::shared_ptr<const std::vector<double>> correction = nullptr)
      : var_px2(var),
        lattice_share(share),
        optics_excess(excess),
        edge_correction(std::move(correction)) {}
  double var_px2;
  double lattice_share;
  double optics_excess;
  std::shared_ptr<const std::vector<double>> edge_correction;
};
// The crosstalk as a total blur `blur_var_px2` (pixel area included) leaves room for: its
// variance at most the blur less the pixel's area and the optics' floor (kMinOpticsVarPx2). Below
// that kink a frame's blur comes off the crosstalk, the optics kept at their floor, and a search
// of the blur goes on past it: a sensor whose blur is all after the pixels has its truth on the
// kink, and a search that stopped there lost the noisy frames that ask for less blur.
inline double CrosstalkRoomPx2(double blur_var_px2) { return blur_var_px2 - kLeastBlurVarPx2; }
inline Crosstalk RoomFor(const Crosstalk& c, double blur_var_px2) {
  return {std::min(c.var_px2, CrosstalkRoomPx2(blur_var_px2)), c.lattice_share, c.optics_excess,
          c.edge_correction};
}

struct BlobFitResult {
  bool ok = false;
  cv::Point2d center_px;
  // The disc's variance along its axes (no blur), A^2/4 and B^2/4, with the anisotropy's noise
  // bias removed by the continuous round-blob rule (psf_anisotropy.h DenoisedAnisotropy2).
  double major_var_px2 = 0.0;
  double minor_var_px2 = 0.0;
  double raw_major_var_px2 = 0.0;  // the same from the fitted P's eigenvalues as they are
  double raw_minor_var_px2 = 0.0;
  // E |a_noise|^2 of P's anisotropy a = ((P11 - P22) / 2, P12), px^-4, from the fit's covariance
  // (NaN when it could not be computed: then nothing is removed).
  double anisotropy_noise_var = 0.0;
  // The disc's trace size 1 / (2 tr P) (px^2, no blur: a circle's A^2/4, an ellipse's harmonic
  // mean of its axes' variances) and its standard error from the fit's covariance (the frame's
  // own noise, widened by sqrt(chi2_per_pixel) when the fit misses its pixels by more than their
  // noise); NaN when not computed (a single pass, or a singular fit). Linear in P, free of the
  // round-blob rule's shrink: the motion check's size (bracket_checks.h CheckMotionOfSizes).
  double trace_var_px2 = std::numeric_limits<double>::quiet_NaN();
  double trace_var_se_px2 = std::numeric_limits<double>::quiet_NaN();
  // The standard error of major_var_px2 (the round-blob rule's slope included); NaN as above.
  double major_var_se_px2 = std::numeric_limits<double>::quiet_NaN();
  double angle_deg = 0.0;      // major axis direction, degrees from +x
  double blur_var_px2 = 0.0;   // the calibrated blur variance used (pixel area included)
  double crosstalk_var_px2 = 0.0;  // the part of it after the sampling, as used
  double chi2_per_pixel = 0.0; // weighted residual sum of squares / pixels (~1 when the model fits)
  // The disc's brightness and the background under it, in full scale (1 = 2^bit_depth - 1).
  double amplitude = 0.0, background = 0.0;
  // The same after the first pass, weighted by the read noise alone (FitBlurSplit compares it).
  double read_weighted_chi2 = 0.0;
  int pixels = 0;
};

// Fits one frame's blob. image: the CV_16UC1 frame the features were computed on (bit_depth
// significant bits); blur_var_px2: the blur variance per axis, pixel area included (> 1/12).
// Returns ok = false when the features have no usable blob or the fit fails.
// crosstalk: the part of the blur that comes after the pixels sample the image (inter-pixel
// crosstalk), its variance on the pixel grid and its kernel's shape; the rest of the blur, less
// the pixel's area, is the optics' before them (BlurCalibration::crosstalk_*, FitBlurSplit).
// psf: the optics' PSF anisotropy (an astigmatic lens; BlurCalibration::psf_aniso_*): each edge
// point blurred by n^T S n for its normal n.
BlobFitResult FitBlob(const cv::Mat& image, int bit_depth, const Features& features,
                      double blur_var_px2, const Crosstalk& crosstalk = {},
                      const PsfAnisotropy& psf = {});

// FitBlob with `passes` passes (2: FitBlob's; 1: the read noise's weights alone, whose
// BlobFitResult::read_weighted_chi2 FitBlurSplit minimises, without errors).
BlobFitResult FitBlobPasses(const cv::Mat& image, int bit_depth, const Features& features,
                            double blur_var_px2, const Crosstalk& crosstalk, int passes,
                            const PsfAnisotropy& psf = {});

// The one-pass cost (FitBlobPasses with passes 1: the read noise's weights) as a function of the
// blur variance, around `blur_var_px2`: the Gauss-Newton system of the fit with the blur as an
// eighth parameter, at the one-pass solution, the blur's column by a forward difference of the
// model. Profiled over the other seven (the Schur complement), the cost's minimum lies `step_px2`
// from the given blur, with the standard error `se_px2` (its curvature, scaled by the cost per
// pixel: the read noise's weights understate a shot-noise-limited frame's noise), and the raw
// disc variances (BlobFitResult::raw_*) move along the blur with the slopes given. One fit and
// one model evaluation: the frame's own blur where it lies near the given one (refocus.h).
struct BlobBlurProfile {
  bool ok = false;
  double per_pixel = 0.0;    // the one-pass cost per pixel at the given blur
  double step_px2 = 0.0;     // the cost's minimum less the given blur (Gauss-Newton)
  double se_px2 = 0.0;       // its standard error
  double major_slope = 0.0;  // d raw_major_var_px2 / d blur, the fit re-solved
  double minor_slope = 0.0;
};
BlobBlurProfile ProfileBlobBlur(const cv::Mat& image, int bit_depth, const Features& features,
                                double blur_var_px2, const Crosstalk& crosstalk,
                                const PsfAnisotropy& psf = {});

// The one-pass cost (FitBlobPasses with passes 1, the read noise's weights: what FitBlurSplit
// sums) around the blur `blur_var_px2` and the crosstalk's variance, as ProfileBlobBlur with two
// more parameters: the blur (the crosstalk kept) and the crosstalk's variance (the blur kept: the
// optics lose what it gains), profiled over the disc's seven. Half the cost's gradient (J^T r)
// and its Gauss-Newton curvature (J^T J) in the two, in the frame's raw read-weighted units, so
// that frames' profiles add (estimator/blur_level.h BlurSplitRefiner). One fit and two model
// evaluations; a round PSF.
struct BlobSplitProfile {
  bool ok = false;
  double gradient[2] = {0.0, 0.0};  // (blur, crosstalk)
  double curvature[2][2] = {{0.0, 0.0}, {0.0, 0.0}};
  double cost = 0.0;  // the one-pass cost there (read-weighted chi-square, summed over pixels)
};
BlobSplitProfile ProfileBlobSplit(const cv::Mat& image, int bit_depth, const Features& features,
                                  double blur_var_px2, const Crosstalk& crosstalk);

// The PSF anisotropy a calibrated blur holds (BlurCalibration::psf_aniso_*).
inline PsfAnisotropy PsfOf(const BlurCalibration& b) {
  PsfAnisotropy psf;
  psf.c_px2 = b.psf_aniso_c_px2, psf.s_px2 = b.psf_aniso_s_px2;
  return psf;
}

// The blur the blob fit is given for a frame: at the distance its moments give through the
// geometric model, the calibrated blur (BlurCalibration, measured on every calibration frame from
// the blob's cumulants, crosstalk included) where the model has it, else the geometric model's
// b(u). 0 when the model has no geometric fit or the moments give no distance.
double BlobFitBlurVarPx2(const CalibrationModel& model, const Features& features);

// The default path's hook: the features' moments less the model's PSF anisotropy
// (RemovePsfAnisotropy, kept even when the fit fails), the blur (BlobFitBlurVarPx2), FitBlob with
// the model's crosstalk split and PSF anisotropy, and the features' moment variances replaced by
// the fit's (disc + that blur). The calibration fits its geometric model on these same sizes (a
// second pass, app/processing/recording_fit.cc), so measurement and calibration see one size.
// Leaves the sizes the moments' (less the PSF anisotropy) when the model has no geometric fit or
// the blob fit fails. Returns whether it replaced.
bool RefineWithBlobFit(const cv::Mat& image, int bit_depth, const CalibrationModel& model,
                       Features* features);

// One calibration frame for FitBlurSplit: the frame, its features and the calibrated blur at
// its distance (pixel area included).
struct CrosstalkFrame {
  cv::Mat image;  // CV_16UC1
  int bit_depth = 12;
  Features features;
  double blur_var_px2 = 0.0;
  double d_mm = 0.0;  // the frame's distance (the offset's slope in 1000 / d); 0: unknown
  // u = 1000 / d_mm, the offset's variable (0 when the distance is unknown).
  double InverseMetres() const { return d_mm > 0.0 ? 1000.0 / d_mm : 0.0; }
  // Its given blur plus an offset's curve o0 + o1 u + o2 u^2.
  double BlurWithOffset(double o0, double o1, double o2) const {
    return blur_var_px2 + OffsetCurvePx2(o0, o1, o2, InverseMetres());
  }
};

// The split of the calibrated blur: the variance (px^2) of the part that comes after
// the pixels sample the image (inter-pixel crosstalk; the rest, less the pixel's area, is the
// optics' before them), as the one that fits the frames best: the blob fit's first-pass
// residuals summed over the frames, minimised by Brent's method (Boost). The edge's shape on the
// pixels tells the two blurs apart where the optics are sharp (a sharp image spread after the
// sampling is not a blurred one sampled); at 0.7 px of optics and more they shape the edge alike
// and either split serves. The kernel's shape is fitted too (Crosstalk::lattice_share): with a
// sampled Gaussian alone a lattice walk of variance 0.64 read 0.25. And the blob fit's own total
// blur, as a line in 1000 / d from the frames' given blur (each frame's best blur at the split;
// CrosstalkFrame::d_mm). And the optics' edge beyond a Gaussian's (Crosstalk::optics_excess),
// where the frames ask for it materially: the first two rounds run from a Gaussian edge and
// from the optics' own edge fitted first, the cheaper in cost is kept, and a non-Gaussian edge
// is refined in each later round. Where the crosstalk reaches the room the frames' least blur
// leaves it (RoomFor), the sensor whose blur is all after the pixels is tried (every frame on
// that kink). Coordinate descent, kSplitRounds rounds. No crosstalk when no frame is usable or
// the optics alone fit best. About 500 one-pass blob fits per frame (6 s for 32 frames; a
// non-Gaussian edge about twice that): give it a few dozen frames across the calibrated
// distances.
struct BlurSplit {
  double crosstalk_var_px2 = 0.0;
  double crosstalk_lattice_share = 0.0;  // the kernel's shape (Crosstalk)
  double optics_excess = 0.0;            // the optics' line spread's excess kurtosis (Crosstalk)
  // The total blur's correction (px^2): blur_offset_px2 + blur_offset_u_px2 u + blur_offset_u2_px2
  // u^2 (u = 1000 / d_mm) added to the frames' given blur, fitted with the split: the blob fit's
  // axis ratio needs the blur to a few 0.001 px^2 where the optics are sharp (0.03 px^2 off swings
  // theta by 0.1-0.3 deg with the edges' phases), finer than the cumulants measure it; and a lens
  // whose PSF has no second moment (the Airy pattern's r^-3 tail) gives the cumulants a blur that
  // bends with the disc's size unlike the fit's own (docs/estimator.md "The blob fit's blur bends
  // with the cumulants'"), hence the curve.
  double blur_offset_px2 = 0.0;
  double blur_offset_u_px2 = 0.0;
  double blur_offset_u2_px2 = 0.0;
  int frames = 0;  // the frames that took part
  // The frames the offset's curve was refitted on (estimator/blur_level.h BlurLevelLine); 0: the
  // curve is the split's frames'.
  int level_frames = 0;
  // The offset at u = 1000 / d_mm (px^2).
  double OffsetPx2(double u) const {
    return OffsetCurvePx2(blur_offset_px2, blur_offset_u_px2, blur_offset_u2_px2, u);
  }
  // The blob fit's blur for `frame`: its given blur plus the offset's curve.
  double FitBlurAt(const CrosstalkFrame& frame) const {
    return frame.blur_var_px2 + OffsetPx2(frame.InverseMetres());
  }
};
BlurSplit FitBlurSplit(const std::vector<CrosstalkFrame>& frames);
// The most calibration frames FitBlurSplit is given (`irdist fit`, the accuracy study, the phase
// sweep), spread over the calibration's: every k-th of them (SplitFramesOf).
constexpr std::size_t kBlurSplitFrames = 32;
std::vector<CrosstalkFrame> SplitFramesOf(const std::vector<CrosstalkFrame>& frames);

namespace blob_model {
struct PixelResponse;  // estimator/blob_pixel_model.h (estimator-internal)
}
// The blob fit's pixel response for a blur of `blur_var_px2` (pixel area included): the crosstalk's
// share of it and kernel, the optics' edge and its correction, the PSF's anisotropy.
blob_model::PixelResponse ResponseOf(double blur_var_px2, const Crosstalk& crosstalk,
                                     const PsfAnisotropy& psf);

// The response after the blur a model's blur calibration or a split gives the blob fit.
inline Crosstalk CrosstalkOf(const BlurCalibration& b) {
  return {b.crosstalk_var_px2, b.crosstalk_lattice_share, b.optics_excess,
          b.edge_correction.empty()
              ? nullptr
              : std::make_shared<const std::vector<double>>(b.edge_correction)};
}
inline Crosstalk CrosstalkOf(const BlurSplit& s) {
  return {s.crosstalk_var_px2, s.crosstalk_lattice_share, s.optics_excess};
}
// A fitted split into a model's blur calibration: the response after the blur and the blob
// fit's own blur offset (its curve in 1000 / d).
inline void SetSplit(const BlurSplit& s, BlurCalibration* b) {
  b->crosstalk_var_px2 = s.crosstalk_var_px2;
  b->crosstalk_lattice_share = s.crosstalk_lattice_share;
  b->optics_excess = s.optics_excess;
  b->fit_offset_px2 = s.blur_offset_px2;
  b->fit_offset_u_px2 = s.blur_offset_u_px2;
  b->fit_offset_u2_px2 = s.blur_offset_u2_px2;
}

}  // namespace irdist
