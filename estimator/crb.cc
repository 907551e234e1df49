#include "estimator/crb.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "base/check.h"
#include "base/pi.h"

namespace irdist {
namespace {


}  // namespace

double PixelNoise::VarianceE2(double signal_e) const {
  const double quant_e2 =
      system_gain_dn_per_e > 0.0 ? 1.0 / (12.0 * system_gain_dn_per_e * system_gain_dn_per_e) : 0.0;
  return std::max(0.0, signal_e) + dark_e + read_noise_e * read_noise_e + quant_e2;
}

bool PixelNoise::IsValid(std::string* why) const {
  if (read_noise_e >= 0.0 && dark_e >= 0.0 && system_gain_dn_per_e >= 0.0) return true;
  if (why) *why = "read_noise_e, dark_e and system_gain_dn_per_e must be >= 0";
  return false;
}

std::string CrbResult::BriefReport() const {
  char text[256];
  if (!valid) return "CRB not computed: the Fisher information is singular";
  if (theta_sd_deg >= 0) {
    std::snprintf(
        text, sizeof(text),
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

FisherInformation::FisherInformation()
    : fisher_(cv::Matx<double, kNumCrbParams, kNumCrbParams>::zeros()) {}

void FisherInformation::AddFrame(const FrameSensitivity& frame) {
  std::string why;
  IRDIST_CHECK(frame.noise.IsValid(&why), "FisherInformation: ", why);
  const cv::Mat1d& mu = frame.expected_e;
  for (int k = 0; k < kNumCrbParams; ++k) {
    IRDIST_CHECK(frame.derivatives[k].size() == mu.size(), "FisherInformation: derivative ", k,
                 " is not the size of the expected image");
  }
  for (int y = 0; y < mu.rows; ++y) {
    for (int x = 0; x < mu.cols; ++x) {
      const double var = frame.noise.VarianceE2(mu(y, x));
      if (!(var > 0.0)) continue;  // a noiseless, signal-free pixel carries no information
      double g[kNumCrbParams];
      for (int k = 0; k < kNumCrbParams; ++k) g[k] = frame.derivatives[k](y, x);
      for (int i = 0; i < kNumCrbParams; ++i)
        for (int j = 0; j < kNumCrbParams; ++j) fisher_(i, j) += g[i] * g[j] / var;
    }
  }
}

double FisherInformation::BoundVariance(int param, const std::vector<int>& free_params) const {
  const int n = static_cast<int>(free_params.size());
  const auto where = std::find(free_params.begin(), free_params.end(), param);
  IRDIST_CHECK(where != free_params.end(), "BoundVariance: parameter ", param, " is not free");
  // Scaled to unit diagonal so that the units (mm, rad, px) do not decide the conditioning.
  cv::Mat1d f(n, n), scale(n, 1);
  for (int i = 0; i < n; ++i) {
    const double diag = fisher_(free_params[i], free_params[i]);
    if (!(diag > 0.0)) return std::numeric_limits<double>::quiet_NaN();
    scale(i) = 1.0 / std::sqrt(diag);
  }
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      f(i, j) = fisher_(free_params[i], free_params[j]) * scale(i) * scale(j);
  cv::Mat1d w;
  cv::SVD::compute(f, w);
  if (!(w(n - 1) > 1e-12 * w(0))) return std::numeric_limits<double>::quiet_NaN();
  cv::Mat1d inv;
  cv::invert(f, inv, cv::DECOMP_SVD);
  const int k = static_cast<int>(where - free_params.begin());
  return inv(k, k) * scale(k) * scale(k);
}

CrbResult ComputeFrameCrb(const std::vector<FrameSensitivity>& frames, bool theta_identifiable) {
  FisherInformation info;
  CrbResult out;
  for (const FrameSensitivity& frame : frames) {
    info.AddFrame(frame);
    out.signal_e += cv::sum(frame.expected_e)[0];
    double peak = 0.0;
    cv::minMaxLoc(frame.expected_e, nullptr, &peak);
    out.peak_e = std::max(out.peak_e, peak);
  }
  const std::vector<int> known_theta = {kCrbLnI0, kCrbX, kCrbY, kCrbD};
  const std::vector<int> all = {kCrbLnI0, kCrbTheta, kCrbX, kCrbY, kCrbD};
  const std::vector<int>& free_params = theta_identifiable ? all : known_theta;
  const double d_var = info.BoundVariance(kCrbD, free_params);
  const double d_var_known = info.BoundVariance(kCrbD, known_theta);
  const double theta_var = theta_identifiable ? info.BoundVariance(kCrbTheta, all) : -1.0;
  out.valid = d_var > 0.0 && d_var_known > 0.0 && (!theta_identifiable || theta_var > 0.0);
  if (!out.valid) return out;
  out.d_sd_mm = std::sqrt(d_var);
  out.d_sd_known_theta_mm = std::sqrt(d_var_known);
  out.theta_sd_deg = theta_identifiable ? std::sqrt(theta_var) * 180.0 / kPi : -1.0;
  return out;
}

}  // namespace irdist
