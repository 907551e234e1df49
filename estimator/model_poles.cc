#include "estimator/model_poles.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace irdist {

namespace {

constexpr int kDistanceSteps = 80;   // the sweep over the (widened) calibrated D range
constexpr int kThetaSteps = 8;       // and over the calibrated thetas
constexpr double kVanishing = 1e-9;  // |Den| below this share of its value at the sample

double Denominator(const ModelSpec& spec, const std::vector<double>& c, const double* vars) {
  double powers[kNumModelVars][4];
  PowerTable(vars, powers);
  return SumTerms(spec, spec.num_numerator, spec.num_denominator, c.data(), powers);
}

}  // namespace

std::string PoleScan::Note() const {
  if (!pole) return "";
  std::ostringstream out;
  out.precision(4);
  out << "its denominator vanishes at d = " << d_mm << " mm, theta " << theta_deg
      << " deg, inside the calibrated range (or its margin)";
  return out.str();
}

PoleScan ScanForPoles(const ModelSpec& spec, const std::vector<double>& coefficients,
                      double sigma_deg,
                      const std::vector<std::array<double, kNumModelVars>>& samples,
                      const std::vector<double>& thetas_deg, double d_ref_mm, double d_scale,
                      double margin) {
  PoleScan scan;
  if (!spec.has_denominator() || samples.empty() || thetas_deg.size() != samples.size() ||
      static_cast<int>(coefficients.size()) != spec.num_coefficients() || !(margin >= 0.0)) {
    return scan;
  }
  double d_lo = samples[0][kVarD], d_hi = d_lo;
  const auto [t_lo, t_hi] = std::minmax_element(thetas_deg.begin(), thetas_deg.end());
  for (const auto& s : samples) {
    d_lo = std::min(d_lo, s[kVarD]);
    d_hi = std::max(d_hi, s[kVarD]);
  }
  // D goes as 1 / d^2: the distances' margin widens D's range by (1 + margin)^2 each way.
  const double widen = (1.0 + margin) * (1.0 + margin);
  d_lo /= widen;
  d_hi *= widen;
  for (size_t i = 0; i < samples.size(); ++i) {
    std::array<double, kNumModelVars> v = samples[i];
    v[kVarRho] = Rho(thetas_deg[i], sigma_deg);
    const double tiny = kVanishing * std::fabs(Denominator(spec, coefficients, v.data()));
    for (int b = 0; b <= kThetaSteps; ++b) {
      const double theta = *t_lo + (*t_hi - *t_lo) * b / kThetaSteps;
      v[kVarRho] = Rho(theta, sigma_deg);
      double previous_d = 0.0, previous = 0.0;
      for (int a = 0; a <= kDistanceSteps; ++a) {
        v[kVarD] = d_lo + (d_hi - d_lo) * a / kDistanceSteps;
        const double den = Denominator(spec, coefficients, v.data());
        const bool crossed = a > 0 && den * previous < 0.0;
        if (crossed || std::fabs(den) <= tiny) {
          // The zero between the two steps, linearly (or this step's D when it is there).
          const double at = crossed ? previous_d + (v[kVarD] - previous_d) * previous /
                                                       (previous - den)
                                    : v[kVarD];
          scan.pole = true;
          scan.d_mm = d_ref_mm / std::sqrt(at * d_scale);
          scan.theta_deg = theta;
          return scan;
        }
        previous_d = v[kVarD];
        previous = den;
      }
    }
  }
  return scan;
}

}  // namespace irdist
