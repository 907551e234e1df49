#include "estimator/health.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <map>

#include "estimator/features.h"
#include "estimator/fit.h"

namespace irdist {
namespace {

constexpr double kPixelBoxVar = 1.0 / 12.0;  // the pixel's area, part of every measured blur

// ln sd = ln c + k ln(d / 1000 mm), least squares over the per-distance rms of the residuals.
void FitBlurNoise(const std::map<double, std::pair<double, int>>& groups, BlurCalibration* b) {
  double sw = 0.0, sx = 0.0, sy = 0.0, sxx = 0.0, sxy = 0.0;
  int used = 0;
  for (const auto& [d_mm, acc] : groups) {
    if (acc.second < 3 || !(acc.first > 0.0)) continue;
    const double x = std::log(d_mm / 1000.0), y = 0.5 * std::log(acc.first / acc.second);
    sw += acc.second;
    sx += acc.second * x;
    sy += acc.second * y;
    sxx += acc.second * x * x;
    sxy += acc.second * x * y;
    ++used;
  }
  if (used == 0) return;
  const double var_x = sxx / sw - (sx / sw) * (sx / sw);
  const double k = used >= 2 && var_x > 1e-12 ? (sxy / sw - sx / sw * sy / sw) / var_x : 0.0;
  b->noise_exponent = k;
  b->noise_at_1m_px2 = std::exp(sy / sw - k * sx / sw);
}

}  // namespace

double BlurCalibration::BlurVarPx2(double d_mm) const {
  const double u = 1000.0 / d_mm;
  return c0_px2 + c1_px2 * u + c2_px2 * u * u;
}

double BlurCalibration::NoisePx2(double d_mm) const {
  return noise_at_1m_px2 * std::pow(d_mm / 1000.0, noise_exponent);
}

BlurCalibration FitBlurCalibration(const std::vector<CalibrationSample>& samples) {
  BlurCalibration b;
  std::vector<std::pair<double, double>> points;  // (d, blur var)
  for (const CalibrationSample& s : samples) {
    if (!s.measurement.Usable() || !std::isfinite(s.measurement.blur_var_px2)) continue;
    points.push_back({s.d_mm, s.measurement.blur_var_px2});
  }
  b.frames = static_cast<int>(points.size());
  if (points.size() < 12) return b;
  Eigen::MatrixXd a(points.size(), 3);
  Eigen::VectorXd y(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    const double u = 1000.0 / points[i].first;
    a.row(i) << 1.0, u, u * u;
    y(i) = points[i].second;
  }
  const Eigen::Vector3d c = a.colPivHouseholderQr().solve(y);
  b.c0_px2 = c(0);
  b.c1_px2 = c(1);
  b.c2_px2 = c(2);
  std::map<double, std::pair<double, int>> groups;  // d -> (sum r^2, count)
  for (const auto& p : points) {
    const double r = p.second - b.BlurVarPx2(p.first);
    groups[p.first].first += r * r;
    ++groups[p.first].second;
  }
  FitBlurNoise(groups, &b);
  return b;
}

const char* HealthCheck::Label() const {
  if (!assessed) return "-";
  if (!flagged) return "ok";
  return sigma_change > 0.0 ? "blur_larger" : "blur_smaller";
}

std::string HealthCheck::Advice() const {
  if (!flagged) return "";
  const int percent = static_cast<int>(std::lround(100.0 * sigma_change));
  return std::string("the blob's blur is ") + (percent > 0 ? "+" : "") + std::to_string(percent) +
         "% from the calibration's at this distance: the optics changed (focus ring, lens, "
         "temperature). Restore the calibration's focus, or recalibrate; distances from this "
         "model are biased until then";
}

HealthCheck CheckHealth(const CalibrationModel& model, double d_mm,
                        const std::vector<const Features*>& frames, const HealthOptions& options) {
  HealthCheck h;
  const BlurCalibration& cal = model.blur_calibration;
  if (!cal.fitted() || !(d_mm > 0.0)) return h;
  double sum = 0.0;
  for (const Features* f : frames) {
    if (f == nullptr || !f->Usable() || !std::isfinite(f->blur_var_px2)) continue;
    sum += f->blur_var_px2;
    ++h.frames;
  }
  if (h.frames == 0) return h;
  h.assessed = true;
  h.blur_var_px2 = sum / h.frames;
  h.calibrated_px2 = cal.BlurVarPx2(d_mm);
  h.z = (h.blur_var_px2 - h.calibrated_px2) / (cal.NoisePx2(d_mm) / std::sqrt(h.frames));
  const double measured = std::max(h.blur_var_px2 - kPixelBoxVar, 0.0);
  const double calibrated = std::max(h.calibrated_px2 - kPixelBoxVar, 1e-6);
  h.sigma_change = std::sqrt(measured / calibrated) - 1.0;
  h.flagged = std::fabs(h.z) > options.z_limit && std::fabs(h.sigma_change) > options.min_sigma_change;
  return h;
}

}  // namespace irdist
