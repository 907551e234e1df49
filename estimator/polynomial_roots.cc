#include "estimator/polynomial_roots.h"

#include <Eigen/Dense>
#include <unsupported/Eigen/Polynomials>
#include <algorithm>
#include <cmath>
#include <complex>
#include <utility>

namespace irdist {
namespace {

// Real roots of the polynomial c[0] + c[1] x + ... + c[kDegree] x^kDegree by Eigen's
// PolynomialSolver (eigenvalues of the companion matrix). A root counts as real when its
// imaginary part is below 1e-9 (1 + |real part|): a double root comes out of the eigen solver as
// a pair with imaginary parts of about sqrt(machine epsilon) times its size.
template <int kDegree>
int RealRootsOfDegree(const double* c, double* roots) {
  Eigen::Matrix<double, kDegree + 1, 1> coefficients;
  for (int k = 0; k <= kDegree; ++k) coefficients(k) = c[k];
  Eigen::PolynomialSolver<double, kDegree> solver(coefficients);
  int n = 0;
  for (int i = 0; i < kDegree; ++i) {
    const std::complex<double> z = solver.roots()(i);
    if (std::abs(z.imag()) <= 1e-9 * (1.0 + std::abs(z.real()))) roots[n++] = z.real();
  }
  return n;
}

}  // namespace

// Real roots of poly[0] + poly[1] x + poly[2] x^2 + poly[3] x^3, ascending, each polished by
// three Newton steps. Leading coefficients below 1e-12 of the largest are taken as zero (a lower
// degree). Returns the count.
int RealRoots(const double poly[4], double roots[3]) {
  double scale = 0.0;
  for (int k = 0; k < 4; ++k) scale = std::max(scale, std::abs(poly[k]));
  if (scale == 0.0) return 0;
  double c[4];
  for (int k = 0; k < 4; ++k) c[k] = poly[k] / scale;
  int n = 0;
  if (std::abs(c[3]) > 1e-12) {
    n = RealRootsOfDegree<3>(c, roots);
  } else if (std::abs(c[2]) > 1e-12) {
    n = RealRootsOfDegree<2>(c, roots);
  } else if (std::abs(c[1]) > 1e-12) {
    roots[n++] = -c[0] / c[1];
  }
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) {
      const double x = roots[i];
      const double f = ((c[3] * x + c[2]) * x + c[1]) * x + c[0];
      const double df = (3.0 * c[3] * x + 2.0 * c[2]) * x + c[1];
      if (df != 0.0) roots[i] = x - f / df;
    }
  }
  for (int i = 1; i < n; ++i) {  // ascending (insertion sort of at most three)
    for (int j = i; j > 0 && roots[j - 1] > roots[j]; --j) std::swap(roots[j - 1], roots[j]);
  }
  return n;
}

void NormaliseToUnitNorm(double poly[4]) {
  double norm = 0.0;
  for (int k = 0; k < 4; ++k) norm += poly[k] * poly[k];
  norm = std::sqrt(norm);
  if (norm > 0.0)
    for (int k = 0; k < 4; ++k) poly[k] /= norm;
}

}  // namespace irdist
