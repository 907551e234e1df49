#pragma once
// The standard normal's CDF Phi and density phi from a table, for the blob fit's inner loop
// (estimator/blob_fit.cc: four of each per edge pixel and evaluation; through std::erfc and
// std::exp they were a fifth of the fit's time). Nodes every 1/64 on [-kNormalTableReach,
// kNormalTableReach] hold Phi and phi; between them each is a cubic Hermite interpolant with its
// exact derivatives at the nodes (Phi' = phi, phi' = -x phi): the error is below h^4 / 384 x
// max |f''''| = 2e-10 for Phi and 4e-10 for phi (tests/estimator/normal_table_test.cc measures it
// against erfc and exp), far below a gray level's 1/4095. Beyond the reach Phi is 0 or 1 and phi
// 0 (phi(9) = 1e-18). Inline: the fit calls it about 20,000 times a frame.

#include <cmath>

namespace irdist {

constexpr double kNormalTableReach = 9.0;
constexpr int kNormalTableNodesPerUnit = 64;
constexpr int kNormalTableNodes = static_cast<int>(2 * kNormalTableReach * 64) + 1;

struct NormalValues {
  double cdf;  // Phi(x)
  double pdf;  // phi(x)
};

// The nodes (Phi, phi) at x_i = -kNormalTableReach + i / 64, filled when the program starts (a
// caller during another file's static initialisation would read zeros: there is none).
extern const NormalValues* const kNormalTable;

// Phi(x) and phi(x); NaN gives NaN.
inline NormalValues NormalAt(double x) {
  if (!(x > -kNormalTableReach)) return std::isnan(x) ? NormalValues{x, x} : NormalValues{0, 0};
  if (x >= kNormalTableReach) return {1.0, 0.0};
  constexpr double h = 1.0 / kNormalTableNodesPerUnit;
  const double at = (x + kNormalTableReach) * kNormalTableNodesPerUnit;
  int i = static_cast<int>(at);
  if (i >= kNormalTableNodes - 1) i = kNormalTableNodes - 2;
  const double t = at - i;  // in [0, 1]
  const double x0 = -kNormalTableReach + i * h, x1 = x0 + h;
  const NormalValues a = kNormalTable[i], b = kNormalTable[i + 1];
  // Cubic Hermite basis on [0, 1]; the derivatives scaled by the step.
  const double t2 = t * t, t3 = t2 * t;
  const double h00 = 2 * t3 - 3 * t2 + 1, h10 = (t3 - 2 * t2 + t) * h;
  const double h01 = -2 * t3 + 3 * t2, h11 = (t3 - t2) * h;
  return {h00 * a.cdf + h10 * a.pdf + h01 * b.cdf + h11 * b.pdf,
          h00 * a.pdf - h10 * x0 * a.pdf + h01 * b.pdf - h11 * x1 * b.pdf};
}

}  // namespace irdist
