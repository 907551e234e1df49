#pragma once
// The blob fit's standard errors (estimator/blob_fit.h), from the covariance of its 7 parameters
// (centre x, y; the disc's matrix P11, P12, P22; amplitude; background), the inverse Fisher
// information at the solution: the noise of P's anisotropy (the round-blob rule's input), the
// trace size and its error (the motion check's size), the used major-axis variance's error (the
// fused estimate's per-frame noise). Each needs only the covariance and the solution.

#include <Eigen/Core>

namespace irdist {

using BlobCovariance = Eigen::Matrix<double, 7, 7>;

// E |a_noise|^2 = var a1 + var a2 of P's anisotropy a = ((P11 - P22) / 2, P12), px^-4.
double AnisotropyNoiseVar(const BlobCovariance& c);

// The disc's trace size 1 / (4 p), p = tr(P) / 2 (a circle's A^2/4; an ellipse's harmonic mean of
// its axes' variances), and its standard error d(1 / 4p) = -dp / 4p^2 with dp = (dP11 + dP22) / 2:
// linear in P, without the round-blob rule's shrink, which moves with the frame's signal. A fit
// missing its pixels beyond their noise (chi2 per pixel > 1) widens the error by sqrt(chi2).
void TraceSize(const BlobCovariance& c, const double* v, double chi2_per_pixel, double* var_px2,
               double* se_px2);

// The standard error of the used major-axis variance 1 / (4 p_small), p_small = tr/2 - r with r
// the round-blob rule's |a| (psf_anisotropy.h DenoisedAnisotropy2 of |a|^2 with `noise_var`): the
// gradient of p_small in (P11, P12, P22), the rule's own slope included, through the covariance;
// widened by sqrt(chi2) as above. NaN when it cannot be formed.
double MajorVarSe(const BlobCovariance& c, const double* v, double noise_var, double p_small,
                  double chi2_per_pixel);

}  // namespace irdist
