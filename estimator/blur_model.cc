#include "estimator/blur_model.h"

#include <Eigen/Dense>
#include <cmath>
#include <map>
#include <utility>

namespace irdist {

bool FitNoiseLaw(const std::vector<NoiseGroup>& groups, double* at_1m, double* exponent) {
  double sw = 0.0, sx = 0.0, sy = 0.0, sxx = 0.0, sxy = 0.0;
  int used = 0;
  for (const NoiseGroup& g : groups) {
    if (g.count < 3 || !(g.sum_r2 > 0.0)) continue;
    const double x = g.ln_d_1m, y = 0.5 * std::log(g.sum_r2 / g.count);
    const double w = g.count;
    sw += w;
    sx += w * x;
    sy += w * y;
    sxx += w * x * x;
    sxy += w * x * y;
    ++used;
  }
  if (used == 0) return false;
  const double var_x = sxx / sw - (sx / sw) * (sx / sw);
  const double k = used >= 2 && var_x > 1e-12 ? (sxy / sw - sx / sw * sy / sw) / var_x : 0.0;
  *exponent = k;
  *at_1m = std::exp(sy / sw - k * sx / sw);
  return true;
}

double BlurCalibration::BlurVarPx2(double d_mm) const {
  const double u = 1000.0 / d_mm;
  return c0_px2 + c1_px2 * u + c2_px2 * u * u;
}

double BlurCalibration::NoisePx2(double d_mm) const {
  return noise_at_1m_px2 * std::pow(d_mm / 1000.0, noise_exponent);
}

BlurCalibration FitBlurCalibration(const std::vector<BlurPoint>& points) {
  BlurCalibration b;
  b.frames = static_cast<int>(points.size());
  if (b.frames < kMinBlurCalibrationFrames) return b;
  Eigen::MatrixXd a(points.size(), 3);
  Eigen::VectorXd y(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    const double u = 1000.0 / points[i].d_mm;
    a.row(i) << 1.0, u, u * u;
    y(i) = points[i].blur_var_px2;
  }
  const Eigen::Vector3d c = a.colPivHouseholderQr().solve(y);
  b.c0_px2 = c(0);
  b.c1_px2 = c(1);
  b.c2_px2 = c(2);
  std::map<double, std::pair<double, int>> by_distance;  // d -> (sum r^2, count)
  for (const BlurPoint& p : points) {
    const double r = p.blur_var_px2 - b.BlurVarPx2(p.d_mm);
    by_distance[p.d_mm].first += r * r;
    ++by_distance[p.d_mm].second;
  }
  std::vector<NoiseGroup> groups;
  for (const auto& [d_mm, acc] : by_distance) {
    groups.push_back({std::log(d_mm / 1000.0), acc.first, acc.second});
  }
  FitNoiseLaw(groups, &b.noise_at_1m_px2, &b.noise_exponent);
  return b;
}

}  // namespace irdist
