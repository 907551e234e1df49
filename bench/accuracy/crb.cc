#include "bench/accuracy/crb.h"

#include <cmath>
#include <cstdio>

#include <opencv2/core.hpp>

#include "sim/scene.h"

namespace irdist {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int kCanvas = 96;  // side of the window (px) that holds every rendered blob
enum Param { kLnI0, kTheta, kX, kY, kD, kNumParams };

struct Point {
  double theta_deg, x_px, y_px, d_mm;
};

// Expected signal electrons of one frame on the canvas centred on the sensor.
cv::Mat1d Expected(const sim::RigPhysics& base, const CrbConditions& c, const Point& p,
                   double exposure_ms) {
  sim::RigPhysics physics = base;
  const double pitch_mm = physics.sensor.pixel_pitch_um * 1e-3;
  const double mm_per_px = pitch_mm * p.d_mm / physics.optics.focal_length_mm;
  physics.emitter.offset_x_mm = p.x_px * mm_per_px;
  physics.emitter.offset_y_mm = p.y_px * mm_per_px;
  const sim::Scene scene(physics);
  sim::PoseState pose;
  pose.slide_mm = p.d_mm;
  pose.pan_deg = p.theta_deg;
  pose.bias_ma = c.bias_ma;
  const double intensity = scene.OnAxisIntensityMwSr(c.bias_ma, c.junction_rise_k);
  const sim::SignalWindow w = scene.RenderSignal(pose, intensity, exposure_ms * 1e-3);
  const cv::Rect canvas(physics.sensor.width_px / 2 - kCanvas / 2,
                        physics.sensor.height_px / 2 - kCanvas / 2, kCanvas, kCanvas);
  cv::Mat1d out = cv::Mat1d::zeros(kCanvas, kCanvas);
  const cv::Rect inside = w.rect & canvas;
  cv::Mat1d part;
  w.electrons(inside - w.rect.tl()).convertTo(part, CV_64F);
  part.copyTo(out(inside - canvas.tl()));
  return out;
}

}  // namespace

std::string CrbResult::BriefReport() const {
  char text[256];
  if (theta_sd_deg >= 0) {
    std::snprintf(text, sizeof(text),
                  "CRB d %.2f mm (theta known %.2f mm), theta %.3f deg; signal %.0f e-, peak %.0f e-",
                  d_sd_mm, d_sd_known_theta_mm, theta_sd_deg, signal_e, peak_e);
  } else {
    std::snprintf(text, sizeof(text),
                  "CRB d %.2f mm (theta known %.2f mm), theta not identifiable to first order "
                  "at 0; signal %.0f e-, peak %.0f e-",
                  d_sd_mm, d_sd_known_theta_mm, signal_e, peak_e);
  }
  return text;
}

CrbResult ComputeCrb(const sim::RigPhysics& base, const CrbConditions& c) {
  sim::RigPhysics physics = base;
  physics.optics.supersample = 32;
  const sim::SensorOptions& s = physics.sensor;
  // Steps of the central differences: large enough that the disc's edge crosses many
  // sub-samples, small enough to stay linear.
  const double h[kNumParams] = {0.0, 0.5, 0.25, 0.25, 20.0};
  const Point at{c.theta_deg, 0.0, 0.0, c.d_mm};
  cv::Matx<double, kNumParams, kNumParams> fisher = cv::Matx<double, kNumParams, kNumParams>::zeros();
  CrbResult out;
  for (double t_ms : c.exposures_ms) {
    const cv::Mat1d mu = Expected(physics, c, at, t_ms);
    std::vector<cv::Mat1d> grad(kNumParams);
    grad[kLnI0] = mu.clone();  // d mu / d ln I0 = mu
    for (int k = kTheta; k < kNumParams; ++k) {
      Point plus = at, minus = at;
      double* field = k == kTheta ? &plus.theta_deg : k == kX ? &plus.x_px
                                                     : k == kY ? &plus.y_px
                                                               : &plus.d_mm;
      *field += h[k];
      double* field_m = k == kTheta ? &minus.theta_deg : k == kX ? &minus.x_px
                                                         : k == kY ? &minus.y_px
                                                                   : &minus.d_mm;
      *field_m -= h[k];
      if (k == kTheta && c.theta_deg - h[k] < 0.0) {  // one-sided at theta = 0 (even in theta)
        *field_m = c.theta_deg;
        grad[k] = (Expected(physics, c, plus, t_ms) - Expected(physics, c, minus, t_ms)) / h[k];
      } else {
        grad[k] =
            (Expected(physics, c, plus, t_ms) - Expected(physics, c, minus, t_ms)) / (2 * h[k]);
      }
      if (k == kTheta) grad[k] *= 180.0 / kPi;  // per radian
    }
    // EMVA 1288 variance in electrons^2: shot noise of signal + dark, read noise, quantisation.
    const double dark_e = s.dark_current_e_per_s * t_ms * 1e-3 + s.background_e_per_s * t_ms * 1e-3;
    const double quant_e2 = 1.0 / 12.0 / (s.system_gain_dn_per_e * s.system_gain_dn_per_e);
    for (int y = 0; y < mu.rows; ++y) {
      for (int x = 0; x < mu.cols; ++x) {
        const double var = mu(y, x) + dark_e + s.read_noise_e * s.read_noise_e + quant_e2;
        for (int i = 0; i < kNumParams; ++i)
          for (int j = 0; j < kNumParams; ++j)
            fisher(i, j) += grad[i](y, x) * grad[j](y, x) / var;
      }
    }
    out.signal_e += cv::sum(mu)[0];
    double peak = 0;
    cv::minMaxLoc(mu, nullptr, &peak);
    out.peak_e = std::max(out.peak_e, peak);
  }
  // At theta = 0 the image is even in theta: its first-order information is zero (the one-sided
  // difference above only measures the curvature). Then theta is left out.
  const bool theta_identifiable = c.theta_deg > 0.0;
  auto invert_d = [&](bool with_theta, double* d_var, double* theta_var) {
    std::vector<int> keep;
    for (int i = 0; i < kNumParams; ++i)
      if (i != kTheta || with_theta) keep.push_back(i);
    const int n = static_cast<int>(keep.size());
    cv::Mat1d f(n, n), scale(n, 1);
    for (int i = 0; i < n; ++i) scale(i) = 1.0 / std::sqrt(fisher(keep[i], keep[i]));
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) f(i, j) = fisher(keep[i], keep[j]) * scale(i) * scale(j);
    cv::Mat1d inv;
    cv::invert(f, inv, cv::DECOMP_SVD);
    for (int i = 0; i < n; ++i) {
      const double v = inv(i, i) * scale(i) * scale(i);
      if (keep[i] == kD) *d_var = v;
      if (keep[i] == kTheta && theta_var) *theta_var = v;
    }
  };
  double d_var = 0, theta_var = 0, d_var_known = 0;
  invert_d(theta_identifiable, &d_var, &theta_var);
  invert_d(false, &d_var_known, nullptr);
  out.valid = d_var > 0;
  out.d_sd_mm = std::sqrt(d_var);
  out.d_sd_known_theta_mm = std::sqrt(d_var_known);
  out.theta_sd_deg = theta_identifiable ? std::sqrt(theta_var) * 180.0 / kPi : -1.0;
  return out;
}

}  // namespace irdist
