#pragma once
// Image features of one IRED frame (paper Section 1.1, Table 1): the blob, its ROI, E_rel, F(0,0),
// Sigma, the centroid and the ellipse that gives a first estimate theta0 of the orientation angle.
//
// Conventions (docs/estimator.md):
//  - M_i = g_i / (2^bit_depth - 1): gray levels normalised by the pixel format's maximum, in [0,1].
//    Mono8/10/12/14 content sits in the low bits of the CV_16UC1 image.
//  - E_rel = (1/A) sum_i f(M_i) over the ROI's A pixels, f the inverse response (identity default).
//  - F(0,0) = sum_i M_i over the ROI: the DC term of the unnormalised 2-D DFT (cv::dft) of the ROI
//    divided by the maximum gray level.
//  - Sigma = sqrt((1/A) sum_i (M_i - mean M)^2): population standard deviation of M over the ROI.

#include <opencv2/core.hpp>
#include <limits>
#include <string>
#include <vector>

#include "estimator/ellipse_fit.h"
#include "estimator/scene.h"

namespace irdist {

// How the region of interest is chosen. The same policy must be used in calibration and
// measurement: it is stored in the model file.
enum class RoiPolicy {
  kFixedWindow,  // a square of window_side_px centred on the blob's intensity centroid (default)
  kThreshold,    // the pixels above background + threshold_fraction * (peak - background)
};

// Which ellipse gives Features::theta0_deg.
enum class EllipseMethod {
  kMoments,  // intensity-weighted second moments, background subtracted (default: measured better)
  kContour,  // cv::fitEllipse on the half-maximum contour
  // Least-squares fit (Levenberg-Marquardt, started from the moment ellipse) of a uniformly bright
  // elliptical disc blurred by a Gaussian PSF and integrated over each pixel (3x3 sub-samples) to
  // the blob's pixels; the blur sigma is fitted too (started from psf_sigma_px, or 0.7 px when 0).
  // theta0 = acos(minor / major) of the fitted disc itself (no blur variance to remove).
  kModelFit,
};

// Which pixels enter the second moments (Features::moment_*_var_px2: the geometric baseline's size
// and the ellipse of theta0).
enum class MomentMethod {
  // The pixels above moment_threshold_fraction of the peak. The hard cut through the PSF's wings
  // takes a share of the blob's variance that depends on its size and signal: theta0 biased by
  // +0.3..+0.5 deg at 2.9 m on the virtual rig, and the apparent size by ~0.1 % (docs/estimator.md).
  kThreshold,
  // Every pixel of a circular aperture around the centroid, background-subtracted with the mean
  // of the window outside it (no threshold): the aperture reaches aperture_margin_px beyond the
  // farthest pixel above the moment threshold, so its edge lies in pure noise and the moments
  // are the blob's own for any emitter profile (variances of profile and blur add). The default:
  // theta0 unbiased within 0.03 deg where kThreshold is off by up to 0.5 (docs/estimator.md).
  kAperture,
};

// Which features the inverse response f (FeatureOptions::inverse_response) linearises.
enum class ResponseScope {
  // The paper's use: f enters E_rel only; every other feature reads the raw gray levels (default).
  kERelOnly,
  // Every pixel is linearised before all features (blob, background, centroid, moments, E_rel,
  // F(0,0), Sigma, ellipses): the frame goes through a lookup table holding
  // L(M) = (f(M) - f(0)) / (f(1) - f(0)) on 16 bits (LineariseFrame), the features are computed
  // on it with bit_depth 16, and saturation is counted on the raw frame. L is f up to an affine
  // map, which no feature's linearity depends on; a linear camera's recovered f gives L = M.
  kAllPixels,
};

const char* ToString(RoiPolicy policy);
const char* ToString(EllipseMethod method);
const char* ToString(MomentMethod method);
const char* ToString(ResponseScope scope);  // "e_rel_only", "all_pixels"
// Parse the names ToString gives; return false when the name is unknown.
bool ParseRoiPolicy(const std::string& name, RoiPolicy* policy);
bool ParseEllipseMethod(const std::string& name, EllipseMethod* method);
bool ParseMomentMethod(const std::string& name, MomentMethod* method);
bool ParseResponseScope(const std::string& name, ResponseScope* scope);

// The camera's inverse radiometric response f on normalised gray levels: identity when empty,
// otherwise the piecewise-linear curve through the knots (m_k, f_k), m strictly increasing in [0,1]
// and f non-decreasing (monotone).
struct InverseResponse {
  std::vector<double> m;  // knot abscissae (normalised gray level)
  std::vector<double> f;  // knot values f(m_k)
  bool IsIdentity() const { return m.empty(); }
  double Apply(double normalised_gray) const;
  bool IsValid(std::string* why) const;
};

struct FeatureOptions {
  RoiPolicy roi_policy = RoiPolicy::kFixedWindow;
  // Side of the fixed window (and of the search window around the blob for kThreshold), px. Must
  // hold the whole IRED image at the nearest distance of a recipe.
  int window_side_px = 64;
  // kThreshold: ROI = pixels above background + threshold_fraction * (peak - background).
  double threshold_fraction = 0.05;
  // Pixels above background + moment_threshold_fraction * (peak - background) enter the second
  // moments and the centroid (the rest is noise that would bias them).
  double moment_threshold_fraction = 0.02;
  // Which pixels enter the second moments (see MomentMethod).
  MomentMethod moment_method = MomentMethod::kAperture;
  // kAperture: margin (px) of the aperture beyond the farthest pixel above the moment threshold.
  double aperture_margin_px = 3.0;
  // Blur (Gaussian PSF sigma, px) removed from the second moments before the axis ratio; 0 = none.
  double psf_sigma_px = 0.0;
  // Blob detection runs on the frame downsampled by this factor (area average).
  int detection_downsample = 4;
  // A blob needs a peak at least this fraction of full scale above background (on the coarse pass).
  double min_contrast_fraction = 0.01;
  EllipseMethod ellipse_method = EllipseMethod::kMoments;
  InverseResponse inverse_response;  // identity by default
  // Which features inverse_response linearises (no effect while it is the identity).
  ResponseScope response_scope = ResponseScope::kERelOnly;
  // Estimation only (a model known): the blob's moment variances are replaced by the likelihood
  // fit with the calibrated blur (estimator/blob_fit.h). false = the moments path. Calibration
  // always uses the moments. model.yaml key features.blob_fit (absent = true).
  bool blob_fit = true;
  // The scene pass before the features and the blob fit (estimator/scene.h): defect pixels,
  // other blobs, occlusion. Run by FrameFeatures (app/processing/frame_features.h), not by
  // ComputeFeatures, which measures the frame it is given; CleanScene checks these options.
  SceneOptions scene;
  // E_rel and F(0,0) of the IRED's light alone: the window's own background (the clipped mean of
  // a square four times the window around the blob, beyond its reach; window_background) is
  // taken
  // off every pixel first, so light that does not come from the IRED (ambient light, growing
  // with the exposure) does not enter the differences dE and dF; a constant background (black
  // level) cancels in them either way. Sigma is the same either way. model.yaml key
  // features.subtract_background (absent: false, the paper's features of older models).
  bool subtract_background = true;
  bool IsValid(std::string* why) const;
};

struct Features {
  bool blob_found = false;
  bool touches_border = false;  // ROI clipped by, or blob pixels on, the image border
  bool blob_clipped_by_roi =
      false;                 // blob pixels on the edge of the fixed window (window too small)
  int saturated_pixels = 0;  // pixels at the format's maximum inside the ROI (not averaged away)
  int bit_depth = 0;
  cv::Rect roi;             // fixed window, or the bounding box of the threshold mask
  int roi_area_px = 0;      // A
  double background = 0.0;  // normalised gray level of the background (the frame's median)
  // The window's own background (normalised): what FeatureOptions::subtract_background takes off
  // E_rel and F(0,0), measured only then (0 otherwise).
  double window_background = 0.0;
  double peak = 0.0;        // normalised gray level of the brightest blob pixel
  double e_rel = 0.0;
  double f00 = 0.0;
  double sigma = 0.0;
  cv::Point2d centroid_px;  // background-subtracted intensity centroid
  double moment_major_var_px2 =
      0.0;  // eigenvalues of the intensity-weighted covariance (no PSF removal)
  double moment_minor_var_px2 = 0.0;
  // kAperture: the blur's variance (px^2, per axis, pixel area included) measured on the frame
  // from the blob's 2nd and 4th cumulants along its axes (independent of d and theta for a
  // uniformly bright disc); NaN when not measured. Calibration health compares it with the
  // calibrated blur (health.h).
  double blur_var_px2 = std::numeric_limits<double>::quiet_NaN();
  // The blur variance (px^2, pixel area included) inside moment_*_var_px2 where the blob fit set
  // them (its calibrated blur, estimator/blob_fit.h); NaN for the moments' own.
  double size_blur_var_px2 = std::numeric_limits<double>::quiet_NaN();
  // Where the blob fit set the sizes: its trace size (px^2, the same blur added) and that size's
  // standard error from the frame's own noise (estimator/blob_fit.h); NaN otherwise.
  double trace_var_px2 = std::numeric_limits<double>::quiet_NaN();
  double trace_var_se_px2 = std::numeric_limits<double>::quiet_NaN();
  // And the standard error of moment_major_var_px2 where the blob fit set it; NaN otherwise.
  double major_var_se_px2 = std::numeric_limits<double>::quiet_NaN();
  // The blob fit's disc before the round-blob rule: its variances along its axes (px^2, no blur),
  // its major axis's direction in the camera's axes (deg; the moment ellipse's angle is turned by
  // the line of sight, and a round blob's is then the turn's own) and the noise E|a_noise|^2 of
  // P's anisotropy (px^-4), which a bracket's frames pool (round_blob.h); NaN otherwise.
  double disc_raw_major_var_px2 = std::numeric_limits<double>::quiet_NaN();
  double disc_raw_minor_var_px2 = std::numeric_limits<double>::quiet_NaN();
  double disc_raw_angle_deg = std::numeric_limits<double>::quiet_NaN();
  double disc_aniso_noise_var = std::numeric_limits<double>::quiet_NaN();
  // The blob fit's own blur (estimator/refocus.h MeasureOwnBlur): the blur variance (px^2, pixel
  // area and crosstalk included) that fits this frame best, its standard error, the disc's
  // variances along its axes at that blur (no blur added) and their slopes d(disc var)/d(blur
  // var). NaN when not measured (no model, the moments path, no blob).
  double own_blur_var_px2 = std::numeric_limits<double>::quiet_NaN();
  double own_blur_se_px2 = std::numeric_limits<double>::quiet_NaN();
  double own_major_var_px2 = std::numeric_limits<double>::quiet_NaN();
  double own_minor_var_px2 = std::numeric_limits<double>::quiet_NaN();
  double own_major_slope = std::numeric_limits<double>::quiet_NaN();
  double own_minor_slope = std::numeric_limits<double>::quiet_NaN();
  EllipseFit ellipse_moments;
  EllipseFit ellipse_contour;
  EllipseFit ellipse_model;     // kModelFit only (valid = false under the other methods)
  double model_blur_px = 0.0;   // kModelFit: the fitted Gaussian blur sigma (pixel area excluded)
  double model_rms = 0.0;       // kModelFit: rms residual of the fit, normalised gray levels
  double theta0_deg = 0.0;  // from the ellipse chosen by FeatureOptions::ellipse_method
  // What the scene pass found on the frame before these features (assessed = false when it did
  // not run: ComputeFeatures alone never runs it).
  SceneReport scene;
  // True when the features can be used: a blob, no saturation, not on the border, not clipped.
  bool Usable() const {
    return blob_found && !touches_border && !blob_clipped_by_roi && saturated_pixels == 0;
  }
  std::string BriefReport() const;
};

// The features as the paper's pipeline uses them (fixed window, for the paper-method report).
FeatureOptions PaperFeatureOptions();

// Computes the features of one frame. image: CV_16UC1 holding Mono8/10/12/14/16 content in its low
// bit_depth bits. Throws CheckError on a wrong type/bit depth or invalid options. An image without
// a blob gives blob_found = false (a value, not an error).
Features ComputeFeatures(const cv::Mat& image, int bit_depth, const FeatureOptions& options);

// The coarse pass's image: the mean of each k x k block of `image`, as cv::resize(INTER_AREA)
// gives it (the same values, rounding included), computed by block sums (4-5x faster on CV_16UC1
// with sides that are multiples of k; other images go to cv::resize itself).
cv::Mat DownsampleArea(const cv::Mat& image, int k);

// A Gaussian noise's sd from samples of it around a level: 1.4826 x the median absolute deviation
// from their median (robust to the few that are not noise). Reorders `values`; 0 when empty.
double RobustNoiseSd(std::vector<double>* values);

// The frame through the lookup table of ResponseScope::kAllPixels: every gray level g of the
// CV_16UC1 `image` (bit_depth significant bits) becomes round(65535 L(g / (2^bit_depth - 1))),
// L(M) = (f(M) - f(0)) / (f(1) - f(0)) clamped to [0,1]. Returns a CV_16UC1 image of 16 bits.
// Throws CheckError when the curve is the identity, invalid, or has f(1) == f(0).
cv::Mat LineariseFrame(const cv::Mat& image, int bit_depth, const InverseResponse& curve);

}  // namespace irdist
