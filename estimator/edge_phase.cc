#include "estimator/edge_phase.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>

#include "base/pi.h"

namespace irdist {

EdgePhase EdgePhaseOf(const std::vector<EdgePhaseSample>& samples) {
  std::vector<const EdgePhaseSample*> usable;
  for (const EdgePhaseSample& s : samples) {
    if (s.size_var_px2 > 0.0 && s.d_mm > 0.0 && std::isfinite(s.center_x_px) &&
        std::isfinite(s.center_y_px)) {
      usable.push_back(&s);
    }
  }
  EdgePhase out;
  out.samples = static_cast<int>(usable.size());
  if (out.samples < kMinEdgePhaseSamples) return out;
  constexpr int kSmooth = 3, kColumns = kSmooth + 4;
  Eigen::MatrixXd a(usable.size(), kColumns);
  Eigen::VectorXd y(usable.size());
  for (size_t i = 0; i < usable.size(); ++i) {
    const EdgePhaseSample& s = *usable[i];
    const double radius = 2.0 * std::sqrt(s.size_var_px2);
    const double u = 1000.0 / s.d_mm;
    a(i, 0) = 1.0;
    a(i, 1) = u;
    a(i, 2) = u * u;
    for (int m = 1; m <= 2; ++m) {
      const double w = std::cos(2.0 * kPi * m * s.center_x_px) +
                       std::cos(2.0 * kPi * m * s.center_y_px);
      a(i, kSmooth + 2 * (m - 1)) = w * std::cos(2.0 * kPi * m * radius);
      a(i, kSmooth + 2 * (m - 1) + 1) = w * std::sin(2.0 * kPi * m * radius);
    }
    y(i) = std::log(radius * s.d_mm / 1000.0);
  }
  const Eigen::VectorXd c = a.colPivHouseholderQr().solve(y);
  const Eigen::VectorXd harmonic = a.rightCols(4) * c.tail(4);
  const Eigen::VectorXd residual = y - a * c;
  const double n = static_cast<double>(usable.size());
  out.rms = std::sqrt(harmonic.squaredNorm() / n);
  out.peak_to_peak = harmonic.maxCoeff() - harmonic.minCoeff();
  const double dof = std::max(n - kColumns, 1.0);
  out.noise_rms = std::sqrt(residual.squaredNorm() / dof) * std::sqrt(4.0 / n);
  for (int k = 0; k < kSmooth; ++k) out.smooth[k] = c(k);
  out.ok = true;
  return out;
}

}  // namespace irdist
