#include "estimator/health.h"

#include <algorithm>
#include <cmath>

#include "base/check.h"
#include "estimator/features.h"
#include "estimator/fit.h"
#include "estimator/refocus.h"

namespace irdist {

const char* HealthCheck::Label() const {
  if (!assessed) return "-";
  if (!flagged) return "ok";
  return sigma_change > 0.0 ? "blur_larger" : "blur_smaller";
}

std::string HealthCheck::Advice() const {
  if (!flagged) return "";
  const int percent = static_cast<int>(std::lround(100.0 * sigma_change));
  const std::string head = std::string("the blob's blur is ") + (percent > 0 ? "+" : "") +
                           std::to_string(percent) +
                           "% from the calibration's at this distance: the optics changed (focus "
                           "ring, lens, temperature). Restore the calibration's focus, or "
                           "recalibrate; ";
  if (refocused) {
    return head + "until then each bracket is measured with its own blur (flag refocused), its "
                  "standard error grown by the blur's";
  }
  return head + "distances from this model are biased until then";
}

double BlurSigmaChange(double measured_var_px2, double calibrated_var_px2) {
  const double measured = std::max(measured_var_px2 - kPixelAreaVarPx2, 0.0);
  const double calibrated = std::max(calibrated_var_px2 - kPixelAreaVarPx2, 1e-6);
  return std::sqrt(measured / calibrated) - 1.0;
}

namespace {

// The blob-fit figure (refocus.h FitBracketBlur) when every usable frame has an own blur.
bool BlobFitHealth(const std::vector<const Features*>& frames, HealthCheck* h) {
  std::vector<const Features*> usable;
  for (const Features* f : frames) {
    if (f != nullptr && f->Usable()) usable.push_back(f);
  }
  const BracketBlur blur = FitBracketBlur(usable);
  if (blur.frames == 0 || blur.frames != static_cast<int>(usable.size())) return false;
  h->assessed = h->blob_fit = true;
  h->frames = blur.frames;
  h->blur_var_px2 = blur.blur_var_px2;
  h->blur_se_px2 = blur.se_px2;
  h->calibrated_px2 = blur.calibrated_px2;
  h->z = (blur.blur_var_px2 - blur.calibrated_px2) / blur.se_px2;
  return true;
}

// The cumulants' figure at d_mm.
void CumulantHealth(const BlurCalibration& cal, double d_mm,
                    const std::vector<const Features*>& frames, HealthCheck* h) {
  double sum = 0.0;
  for (const Features* f : frames) {
    if (f == nullptr || !f->Usable() || !std::isfinite(f->blur_var_px2)) continue;
    sum += f->blur_var_px2;
    ++h->frames;
  }
  if (h->frames == 0) return;
  h->assessed = true;
  h->blur_var_px2 = sum / h->frames;
  h->calibrated_px2 = cal.BlurVarPx2(d_mm);
  h->z = (h->blur_var_px2 - h->calibrated_px2) / (cal.NoisePx2(d_mm) / std::sqrt(h->frames));
}

}  // namespace

bool HealthOptions::IsValid(std::string* why) const {
  std::string reason;
  if (!(z_limit > 0.0 && z_limit <= 100.0)) {
    reason = "z_limit not in (0, 100] standard errors";
  } else if (!(min_sigma_change >= 0.0 && min_sigma_change < 1.0)) {
    reason = "min_sigma_change not in [0, 1) (a relative change of the blur's sigma)";
  }
  if (why != nullptr) *why = reason;
  return reason.empty();
}

HealthCheck CheckHealth(const CalibrationModel& model, double d_mm,
                        const std::vector<const Features*>& frames, const HealthOptions& options) {
  std::string why;
  IRDIST_CHECK(options.IsValid(&why), "HealthOptions: " + why);
  HealthCheck h;
  const BlurCalibration& cal = model.blur_calibration;
  if (!cal.fitted()) return h;
  if (!BlobFitHealth(frames, &h)) {
    if (!(d_mm > 0.0)) return h;
    CumulantHealth(cal, d_mm, frames, &h);
    if (!h.assessed) return h;
  }
  h.sigma_change = BlurSigmaChange(h.blur_var_px2, h.calibrated_px2);
  h.flagged = std::fabs(h.z) > options.z_limit && std::fabs(h.sigma_change) > options.min_sigma_change;
  return h;
}

}  // namespace irdist
