#include "estimator/round_blob.h"

#include <algorithm>
#include <cmath>

#include "base/pi.h"
#include "estimator/psf_anisotropy.h"

namespace irdist {
namespace {

// A frame's fitted anisotropy: a (px^-2), its noise E|a_noise|^2 (px^-4) and the |a| its own
// rule kept; false when the frame has none.
struct FrameAnisotropy {
  double c = 0.0, s = 0.0, noise_var = 0.0, own_root = 0.0;
};
bool AnisotropyOf(const Features& f, FrameAnisotropy* out) {
  const double raw_major = f.disc_raw_major_var_px2, raw_minor = f.disc_raw_minor_var_px2;
  const double noise = f.disc_aniso_noise_var;
  if (!(raw_minor > 0.0) || !(raw_major >= raw_minor) || !(noise > 0.0) || !std::isfinite(noise) ||
      !std::isfinite(f.disc_raw_angle_deg)) {
    return false;
  }
  // P's eigenvalues 1 / (4 var): its smaller one along the major axis, at angle phi; a points
  // along -(cos 2 phi, sin 2 phi) (blob_fit.cc DiscEigenvalues).
  const double length = 0.5 * (0.25 / raw_minor - 0.25 / raw_major);
  const double turn = 2.0 * f.disc_raw_angle_deg * kPi / 180.0;
  out->c = -length * std::cos(turn);
  out->s = -length * std::sin(turn);
  out->noise_var = noise;
  out->own_root = std::sqrt(std::max(0.0, DenoisedAnisotropy2(length * length, noise)));
  return true;
}

// The frame's axes with |a| moved by `step` (px^-2), P's trace kept.
void MoveRoot(double step, Features* f) {
  const double blur = f->size_blur_var_px2;
  const double major = f->moment_major_var_px2 - blur, minor = f->moment_minor_var_px2 - blur;
  if (!(minor > 0.0) || !(major > 0.0)) return;
  const double p_small = 0.25 / major, p_large = 0.25 / minor;
  const double half_trace = 0.5 * (p_small + p_large);
  const double root = std::max(0.0, 0.5 * (p_large - p_small) + step);
  if (!(half_trace - root > 0.0)) return;
  f->moment_major_var_px2 = 0.25 / (half_trace - root) + blur;
  f->moment_minor_var_px2 = 0.25 / (half_trace + root) + blur;
}

}  // namespace

void PoolRoundBlobRule(std::vector<Features*> frames) {
  std::vector<FrameAnisotropy> a(frames.size());
  std::vector<bool> has(frames.size(), false);
  double c = 0.0, s = 0.0, precision = 0.0;
  int count = 0;
  for (size_t i = 0; i < frames.size(); ++i) {
    if (!std::isfinite(frames[i]->size_blur_var_px2) || !AnisotropyOf(*frames[i], &a[i])) continue;
    has[i] = true;
    c += a[i].c / a[i].noise_var;
    s += a[i].s / a[i].noise_var;
    precision += 1.0 / a[i].noise_var;
    ++count;
  }
  if (count < 2) return;
  const double pooled2 = (c * c + s * s) / (precision * precision);
  const double root = std::sqrt(
      std::max(0.0, DenoisedAnisotropy2(pooled2, 1.0 / precision, kPooledRoundRuleMidpoint,
                                        kPooledRoundRuleSlope)));
  for (size_t i = 0; i < frames.size(); ++i) {
    if (has[i]) MoveRoot(root - a[i].own_root, frames[i]);
  }
}

void PoolBracket(Features* reference, std::vector<Features>* measurements) {
  std::vector<Features*> frames = {reference};
  for (Features& f : *measurements) frames.push_back(&f);
  PoolRoundBlobRule(frames);
}

}  // namespace irdist
