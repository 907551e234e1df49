#pragma once
// Anisotropy of a blob's image told apart from its causes (docs/estimator.md "Tilt or an
// elliptical PSF"):
// - the optics' PSF anisotropy (an astigmatic lens): the traceless part of the PSF's covariance,
//   a = ((Sxx - Syy) / 2, Sxy) px^2, a constant in pixels, whatever the distance; the face-on
//   calibration frames (theta 0, a round disc) show it alone in their moments;
// - the disc's tilt: its image foreshortened by cos theta, an anisotropy proportional to the
//   disc's image (R^2 / 4 (1 - cos^2 theta) / 2), growing as the disc comes closer;
// - the noise of a round blob's fitted anisotropy (the round-blob rule, DenoisedAnisotropy2).

#include <vector>

#include "estimator/blur_model.h"
#include "estimator/features.h"

namespace irdist {

// The PSF's anisotropy, px^2, in the sensor's axes.
struct PsfAnisotropy {
  double c_px2 = 0.0;  // (Sxx - Syy) / 2
  double s_px2 = 0.0;  // Sxy
  double c_se_px2 = 0.0, s_se_px2 = 0.0;  // their standard errors over the frames
  int frames = 0;      // the face-on frames it was measured on (0: not measured, a round PSF)
  // Whether it stands out of its noise: (c / se_c)^2 + (s / se_s)^2 > kPsfAnisotropySignificance
  // (a chi-square of 2 degrees of freedom beyond its 0.1% tail); a calibration keeps it only then.
  bool Significant() const;
};
constexpr double kPsfAnisotropySignificance = 13.8;

// The PSF's anisotropy from face-on frames' moments (the camera's own axes, before any turn onto
// the line of sight): each frame's covariance anisotropy ((Cxx - Cyy) / 2, Cxy) is the PSF's (a
// round disc's image, a round pixel and crosstalk add none) plus noise of mean 0; their mean over
// the frames, a frame farther than 5 robust sd from the median in either part left out. Fewer
// than kMinPsfAnisotropyFrames usable frames: nothing measured (frames 0, anisotropy 0).
constexpr int kMinPsfAnisotropyFrames = 6;
// The face-on poses, |theta| (deg) at most this, whose frames show the PSF's anisotropy alone.
constexpr double kPsfAnisotropyFaceOnDeg = 0.5;
PsfAnisotropy FitPsfAnisotropy(const std::vector<Features>& face_on);

// Whether a lens can have `psf`: its length below kPsfAnisotropyOfBlur of the optics' least blur
// `least_optics_var_px2` (the calibrated blur less the pixel's area at the range's sharper end):
// a PSF's covariance is positive along every axis, so its anisotropy stays below its own blur. A
// larger one is the scene's (a cut or dirty disc), not the lens's. A calibration keeps the
// anisotropy where it is Significant and possible (KeepsPsfAnisotropy), else takes the PSF as
// round.
constexpr double kPsfAnisotropyOfBlur = 0.9;
bool PsfAnisotropyPossible(const PsfAnisotropy& psf, double least_optics_var_px2);
bool KeepsPsfAnisotropy(const PsfAnisotropy& psf, double least_optics_var_px2);
// `psf` where a calibration keeps it (KeepsPsfAnisotropy), else a round PSF's (c = s = 0).
PsfAnisotropy KeptPsfAnisotropy(const PsfAnisotropy& psf, double least_optics_var_px2);
// A calibration's step (`irdist fit`'s and the accuracy study's): KeptPsfAnisotropy into `blur`
// (its anisotropy, not its noise); whether it was kept.
bool SetPsfAnisotropy(const PsfAnisotropy& psf, double least_optics_var_px2, BlurCalibration* blur);

// The moments' covariance less the PSF's anisotropy: moment_major/minor_var_px2 and the moment
// ellipse's angle become those of C - [[c, s], [s, -c]] (the PSF's round part stays, as the
// calibrated blur b(u) that every size subtracts). Unchanged without usable moments.
void RemovePsfAnisotropy(double c_px2, double s_px2, Features* features);

// The round-blob rule: the squared anisotropy |a|^2 of a fitted disc (P's, px^-4) less its noise,
// continuous in |a|^2. With t = |a|^2 / E|a_noise|^2, the blob is elliptical with the weight
// w(t) = 1 / (1 + e^(k (t0 - t))) (a round blob's |a|^2 is exponential of mean E|a_noise|^2), and
// the estimate is w(t) (|a|^2 - E|a_noise|^2)_+: ~0 for a round blob's noise, the unbiased |a|^2
// for a clearly elliptical one, and no step between. A NaN or negative noise leaves |a|^2 as it is.
// theta grows as |a|^(1/2) near 0 (|a|^2 of 3x the noise reads 4 deg), so a round blob reads
// theta > 2 deg beyond t = 4.6 (1% of frames; the hard step at 4: 1.8%), while a 5 deg blob at
// 2 m on the virtual rig (t ~ 7.5) keeps 95% of its |a|^2. A later midpoint (t0 = 12, k = 1)
// removed every theta-0 outlier on the sharp rig but read that 5 deg blob as 3.7 deg; t0 = 4,
// k = 1 kept too many false ellipses (docs/estimator.md).
constexpr double kRoundRuleMidpoint = 6.0;  // t0
constexpr double kRoundRuleSlope = 2.0;     // k
// `midpoint` and `slope` are t0 and k (the pooled rule's own: round_blob.h).
double DenoisedAnisotropy2(double a2, double noise_var, double midpoint = kRoundRuleMidpoint,
                           double slope = kRoundRuleSlope);

}  // namespace irdist
