#include "estimator/blob_fit_errors.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Dense>

#include "estimator/psf_anisotropy.h"

namespace irdist {

namespace {

// g^T C g over P's entries (P11, P12, P22): the variance of a linear function of P with gradient g.
double PVariance(const BlobCovariance& c, const Eigen::Vector3d& g) {
  const int index[3] = {2, 3, 4};
  double var = 0.0;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) var += g(i) * c(index[i], index[j]) * g(j);
  }
  return var;
}

}  // namespace

double AnisotropyNoiseVar(const BlobCovariance& c) {
  return 0.25 * (c(2, 2) + c(4, 4) - 2.0 * c(2, 4)) + c(3, 3);
}

void TraceSize(const BlobCovariance& c, const double* v, double chi2_per_pixel, double* var_px2,
               double* se_px2) {
  const double p_mean = 0.5 * (v[2] + v[4]);
  const double var_p = PVariance(c, Eigen::Vector3d(0.5, 0.0, 0.5));
  *var_px2 = 0.25 / p_mean;
  *se_px2 = var_p >= 0.0 && p_mean > 0.0
                ? std::sqrt(var_p * std::max(1.0, chi2_per_pixel)) / (4.0 * p_mean * p_mean)
                : std::numeric_limits<double>::quiet_NaN();
}

double MajorVarSe(const BlobCovariance& c, const double* v, double noise_var, double p_small,
                  double chi2_per_pixel) {
  const double a1 = 0.5 * (v[2] - v[4]), a2 = v[3];
  const double norm = std::hypot(a1, a2), n2 = norm * norm;
  const double root = std::sqrt(std::max(0.0, DenoisedAnisotropy2(n2, noise_var)));
  double slope = 0.0;  // d r / d |a|
  if (root > 0.0) {
    const double h = 1e-4 * n2;
    const double dg = (DenoisedAnisotropy2(n2 + h, noise_var) -
                       DenoisedAnisotropy2(n2 - h, noise_var)) / (2.0 * h);
    slope = dg * norm / root;
  }
  Eigen::Vector3d g(0.5, 0.0, 0.5);  // d p_small / d(P11, P12, P22)
  if (norm > 0.0) g -= slope * Eigen::Vector3d(0.5 * a1 / norm, a2 / norm, -0.5 * a1 / norm);
  const double var_p = PVariance(c, g);
  if (!(var_p >= 0.0) || !(p_small > 0.0)) return std::numeric_limits<double>::quiet_NaN();
  return std::sqrt(var_p * std::max(1.0, chi2_per_pixel)) / (4.0 * p_small * p_small);
}

}  // namespace irdist
