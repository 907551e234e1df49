#pragma once
// The real roots of Algorithm 1's start polynomials (Eq. 21, 23, 25: cubics in the scaled D).

namespace irdist {

// Real roots of poly[0] + poly[1] x + poly[2] x^2 + poly[3] x^3, ascending, each polished by
// three Newton steps (Eigen's companion-matrix solver; a root is real when its imaginary part is
// below 1e-9 (1 + |real part|)). Leading coefficients below 1e-12 of the largest are taken as
// zero (a lower degree). Returns the count.
int RealRoots(const double poly[4], double roots[3]);

// poly divided by its Euclidean norm (left as it is when zero).
void NormaliseToUnitNorm(double poly[4]);

}  // namespace irdist
