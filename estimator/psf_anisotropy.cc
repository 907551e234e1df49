#include "estimator/psf_anisotropy.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "base/pi.h"
#include "estimator/features.h"

namespace irdist {
namespace {

double Median(std::vector<double> values) {
  const size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + mid, values.end());
  return values[mid];
}

// The median and a robust sd (features.h RobustNoiseSd: 1.4826 x the median absolute deviation)
// of the values.
void RobustCentre(const std::vector<double>& values, double* median, double* sd) {
  *median = Median(values);
  std::vector<double> scratch = values;
  *sd = RobustNoiseSd(&scratch);
}

}  // namespace

bool PsfAnisotropy::Significant() const {
  if (frames == 0 || !(c_se_px2 > 0.0) || !(s_se_px2 > 0.0)) return false;
  const double zc = c_px2 / c_se_px2, zs = s_px2 / s_se_px2;
  return zc * zc + zs * zs > kPsfAnisotropySignificance;
}

bool PsfAnisotropyPossible(const PsfAnisotropy& psf, double least_optics_var_px2) {
  return std::hypot(psf.c_px2, psf.s_px2) < kPsfAnisotropyOfBlur * least_optics_var_px2;
}

bool KeepsPsfAnisotropy(const PsfAnisotropy& psf, double least_optics_var_px2) {
  return psf.Significant() && PsfAnisotropyPossible(psf, least_optics_var_px2);
}

PsfAnisotropy KeptPsfAnisotropy(const PsfAnisotropy& psf, double least_optics_var_px2) {
  PsfAnisotropy kept = psf;
  if (!KeepsPsfAnisotropy(psf, least_optics_var_px2)) kept.c_px2 = kept.s_px2 = 0.0;
  return kept;
}

bool SetPsfAnisotropy(const PsfAnisotropy& psf, double least_optics_var_px2,
                      BlurCalibration* blur) {
  const PsfAnisotropy kept = KeptPsfAnisotropy(psf, least_optics_var_px2);
  blur->psf_aniso_c_px2 = kept.c_px2;
  blur->psf_aniso_s_px2 = kept.s_px2;
  return KeepsPsfAnisotropy(psf, least_optics_var_px2);
}

PsfAnisotropy FitPsfAnisotropy(const std::vector<Features>& face_on) {
  std::vector<double> c, s;
  for (const Features& f : face_on) {
    if (!f.Usable() || !f.ellipse_moments.valid) continue;
    const double half = 0.5 * (f.moment_major_var_px2 - f.moment_minor_var_px2);
    const double a = 2.0 * f.ellipse_moments.angle_deg * kPi / 180.0;
    if (!std::isfinite(half) || !std::isfinite(a)) continue;
    c.push_back(half * std::cos(a));
    s.push_back(half * std::sin(a));
  }
  PsfAnisotropy out;
  if (static_cast<int>(c.size()) < kMinPsfAnisotropyFrames) return out;
  double c_med, c_sd, s_med, s_sd;
  RobustCentre(c, &c_med, &c_sd);
  RobustCentre(s, &s_med, &s_sd);
  double sum_c = 0, sum_s = 0, sum_cc = 0, sum_ss = 0;
  int n = 0;
  for (size_t i = 0; i < c.size(); ++i) {
    if (std::fabs(c[i] - c_med) > 5.0 * c_sd + 1e-12 ||
        std::fabs(s[i] - s_med) > 5.0 * s_sd + 1e-12) {
      continue;
    }
    sum_c += c[i];
    sum_s += s[i];
    sum_cc += c[i] * c[i];
    sum_ss += s[i] * s[i];
    ++n;
  }
  if (n < kMinPsfAnisotropyFrames) return out;
  out.c_px2 = sum_c / n;
  out.s_px2 = sum_s / n;
  out.c_se_px2 = std::sqrt(std::max(0.0, sum_cc / n - out.c_px2 * out.c_px2) / (n - 1));
  out.s_se_px2 = std::sqrt(std::max(0.0, sum_ss / n - out.s_px2 * out.s_px2) / (n - 1));
  out.frames = n;
  return out;
}

void RemovePsfAnisotropy(double c_px2, double s_px2, Features* f) {
  if ((c_px2 == 0.0 && s_px2 == 0.0) || !f->ellipse_moments.valid) return;
  const double mean = 0.5 * (f->moment_major_var_px2 + f->moment_minor_var_px2);
  const double half = 0.5 * (f->moment_major_var_px2 - f->moment_minor_var_px2);
  const double a = 2.0 * f->ellipse_moments.angle_deg * kPi / 180.0;
  const double c = half * std::cos(a) - c_px2, s = half * std::sin(a) - s_px2;
  const double left = std::hypot(c, s);
  if (!std::isfinite(left)) return;
  f->moment_major_var_px2 = mean + left;
  f->moment_minor_var_px2 = mean - left;
  f->ellipse_moments.angle_deg = 0.5 * std::atan2(s, c) * 180.0 / kPi;
}

double DenoisedAnisotropy2(double a2, double noise_var, double midpoint, double slope) {
  if (!std::isfinite(noise_var) || !(noise_var > 0.0)) return a2;
  const double t = a2 / noise_var;
  const double weight = 1.0 / (1.0 + std::exp(slope * (midpoint - t)));
  return weight * std::max(0.0, a2 - noise_var);
}

}  // namespace irdist
