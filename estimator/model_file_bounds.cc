#include "estimator/model_file_bounds.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "base/bounds.h"

namespace irdist {
namespace {

class Checker {
 public:
  void Value(const std::string& key, double value, const Bound& bound) {
    const std::string refusal = bound.Refusal(key, value);
    if (!refusal.empty()) failures_.push_back({key, refusal});
  }
  void Failure(const std::string& key, const std::string& message) {
    failures_.push_back({key, message});
  }
  std::vector<ModelBoundFailure> Take() { return std::move(failures_); }

 private:
  std::vector<ModelBoundFailure> failures_;
};

// How far a blur variance lies outside bounds::kBlurVarPx2 (0 inside; NaN and inf the farthest).
double Excess(double var_px2) {
  if (bounds::kBlurVarPx2.Contains(var_px2)) return 0.0;
  if (!std::isfinite(var_px2)) return std::numeric_limits<double>::infinity();
  return var_px2 <= bounds::kBlurVarPx2.min ? bounds::kBlurVarPx2.min - var_px2
                                             : var_px2 - bounds::kBlurVarPx2.max;
}

// A blur variance law over the calibrated distances, at 17 distances evenly spaced in u = 1000 / d
// (the law is a quadratic in u): a variance is > 0 and at most the largest blur. The distance
// where it lies farthest outside is named.
template <typename Law>
void BlurOverRange(Checker* c, const std::string& key, const CalibratedRanges& r, Law law,
                   const std::string& what) {
  if (!(r.d_min_mm > 0.0 && r.d_max_mm >= r.d_min_mm)) return;  // ranges are checked on their own
  const double u_near = 1000.0 / r.d_min_mm, u_far = 1000.0 / r.d_max_mm;
  double worst_excess = 0.0, worst_d_mm = 0.0, worst_var_px2 = 0.0;
  for (int i = 0; i <= 16; ++i) {
    const double d_mm = 1000.0 / (u_far + (u_near - u_far) * i / 16.0);
    const double var_px2 = law(d_mm);
    if (Excess(var_px2) > worst_excess) {
      worst_excess = Excess(var_px2);
      worst_d_mm = d_mm;
      worst_var_px2 = var_px2;
    }
  }
  if (worst_excess == 0.0) return;
  c->Failure(key, what + " at d = " + BoundNumber(worst_d_mm) + " mm (inside the calibrated " +
                      BoundNumber(r.d_min_mm) + ".." + BoundNumber(r.d_max_mm) + " mm) is " +
                      BoundNumber(worst_var_px2) + " px^2, outside " +
                      bounds::kBlurVarPx2.RangeText() + " (" + bounds::kBlurVarPx2.why + ")");
}

// The PSF's anisotropy |a| (blur_calibration.psf_aniso_*) is the half difference of the optics'
// two variances: an elliptical PSF has both > 0, so |a| stays below the optics' mean variance (the
// blob fit's blur less the pixel's area and the crosstalk) at every calibrated distance.
void CheckPsfAnisotropy(Checker* c, const BlurCalibration& b, const CalibratedRanges& r) {
  const std::string k = "blur_calibration.";
  c->Value(k + "psf_aniso_c_px2", b.psf_aniso_c_px2, bounds::kBlurOffsetPx2);
  c->Value(k + "psf_aniso_s_px2", b.psf_aniso_s_px2, bounds::kBlurOffsetPx2);
  const double a = std::hypot(b.psf_aniso_c_px2, b.psf_aniso_s_px2);
  if (a == 0.0 || !(r.d_min_mm > 0.0 && r.d_max_mm >= r.d_min_mm)) return;
  for (const double d_mm : {r.d_min_mm, r.d_max_mm}) {
    const double optics = b.FitBlurVarPx2(d_mm) - kPixelAreaVarPx2 - b.crosstalk_var_px2;
    if (a < optics) continue;
    c->Failure(k + "psf_aniso_c_px2",
               "the PSF's anisotropy " + BoundNumber(a) + " px^2 is not below the optics' blur " +
                   BoundNumber(optics) + " px^2 at d = " + BoundNumber(d_mm) +
                   " mm (an elliptical PSF's two variances are both > 0)");
    return;
  }
}

void CheckBlur(Checker* c, const BlurCalibration& b, const CalibratedRanges& r) {
  if (!b.fitted()) return;
  const std::string k = "blur_calibration.";
  c->Value(k + "fit_offset_px2", b.fit_offset_px2, bounds::kBlurOffsetPx2);
  c->Value(k + "fit_offset_u_px2", b.fit_offset_u_px2, bounds::kBlurOffsetPx2);
  c->Value(k + "fit_offset_u2_px2", b.fit_offset_u2_px2, bounds::kBlurOffsetPx2);
  c->Value(k + "noise_at_1m_px2", b.noise_at_1m_px2, bounds::kBlurNoisePx2);
  c->Value(k + "noise_exponent", b.noise_exponent, bounds::kNoiseExponent);
  c->Value(k + "crosstalk_lattice_share", b.crosstalk_lattice_share, bounds::kShare);
  c->Value(k + "optics_excess", b.optics_excess, bounds::kOpticsExcess);
  for (std::size_t i = 0; i < b.edge_correction.size(); ++i) {
    c->Value(k + "edge_correction[" + std::to_string(i) + "]", b.edge_correction[i],
             bounds::kEdgeCorrection);
  }
  BlurOverRange(c, k + "blur_var_px2", r, [&b](double d) { return b.BlurVarPx2(d); },
                "the calibrated blur c0 + c1 u + c2 u^2");
  BlurOverRange(
      c, k + "fit_offset_u_px2", r, [&b](double d) { return b.FitBlurVarPx2(d); },
      "the blob fit's blur (the calibrated blur + fit_offset_px2 + fit_offset_u_px2 u + "
      "fit_offset_u2_px2 u^2)");
  CheckPsfAnisotropy(c, b, r);
}

// The bits of a monochrome GenICam format ("Mono12", "Mono12p", "Mono12Packed": 12), 0 for
// another name.
int BitsOfMonoFormat(const std::string& name) {
  for (const int bits : {8, 10, 12, 14, 16}) {
    const std::string mono = "Mono" + std::to_string(bits);
    if (name == mono || name == mono + "p" || name == mono + "Packed") return bits;
  }
  return 0;
}

void CheckProvenance(Checker* c, const ModelProvenance& p, const FeatureOptions& f) {
  if (!p.known) return;
  const std::string k = "provenance.";
  c->Value(k + "bit_depth", p.bit_depth, bounds::kBitDepth);
  const int format_bits = BitsOfMonoFormat(p.pixel_format);
  if (format_bits == 0) {
    c->Failure(k + "pixel_format", "'" + p.pixel_format + "' is not a monochrome camera format "
                                   "(Mono8, Mono10(p), Mono12(p), Mono12Packed, Mono14, Mono16)");
  } else if (format_bits != p.bit_depth) {
    c->Failure(k + "bit_depth", "bit_depth " + std::to_string(p.bit_depth) + " contradicts "
                                "pixel_format " + p.pixel_format + ", which delivers " +
                                std::to_string(format_bits) + " bits");
  }
  c->Value(k + "t_ref_ms", p.t_ref_ms, bounds::kExposureMs);
  if (p.t_meas_ms.empty()) c->Failure(k + "t_meas_ms", "no measurement exposure");
  for (size_t i = 0; i < p.t_meas_ms.size(); ++i) {
    const std::string key = k + "t_meas_ms[" + std::to_string(i) + "]";
    c->Value(key, p.t_meas_ms[i], bounds::kExposureMs);
    if (!(p.t_meas_ms[i] > p.t_ref_ms)) {
      c->Failure(key, "measurement exposure " + BoundNumber(p.t_meas_ms[i]) +
                          " ms is not longer than the reference t_ref_ms " +
                          BoundNumber(p.t_ref_ms) + " ms (the bracket's order, docs/recipes.md)");
    }
  }
  const int roi_side_px = std::min(p.roi_width, p.roi_height);
  if (roi_side_px > 0 && f.window_side_px > roi_side_px) {
    c->Failure("features.window_side_px",
               "window_side_px " + std::to_string(f.window_side_px) + " is larger than the " +
                   std::to_string(p.roi_width) + " x " + std::to_string(p.roi_height) +
                   " px ROI the model was calibrated on (provenance.roi_px); at most " +
                   std::to_string(roi_side_px));
  }
}

void CheckFitness(Checker* c, const CalibrationFitness& f) {
  if (!f.assessed) return;
  const std::string k = "fitness.";
  for (const auto& [name, value] : {std::pair{"reduced_chi2", f.reduced_chi2},
                                    {"limit", f.limit}, {"pose_limit", f.pose_limit}}) {
    c->Value(k + name, value, bounds::kChiSquare);
  }
  c->Value(k + "tail_probability", f.tail_probability, bounds::kTailProbability);
  c->Value(k + "size_floor", f.size_floor, bounds::kShare);
  c->Value(k + "difference_floor", f.difference_floor, bounds::kShare);
  c->Value(k + "dof", f.dof, bounds::kCount);
  c->Value(k + "poses", f.poses, bounds::kCount);
  c->Value(k + "poses_over", f.poses_over, bounds::kFrameNumber);
  if (f.poses_over > f.poses) c->Failure(k + "poses_over", "more poses over than poses");
  for (size_t i = 0; i < f.worst.size(); ++i) {
    const PoseFitness& p = f.worst[i];
    const std::string w = k + "worst_poses[" + std::to_string(i) + "].";
    c->Value(w + "slide_mm", p.pose.slide_mm, bounds::kSlideMm);
    c->Value(w + "pan_deg", p.pose.pan_deg, bounds::kAngleDeg);
    c->Value(w + "tilt_deg", p.pose.tilt_deg, bounds::kAngleDeg);
    c->Value(w + "bias_ma", p.pose.bias_ma, bounds::kCurrentMa);
    c->Value(w + "chi2", p.chi2, bounds::kChiSquare);
    c->Value(w + "channels", p.channels, bounds::kCount);
    c->Value(w + "scatter_ratio", p.scatter_ratio, bounds::kChiSquare);
    c->Value(w + "residual_percent", p.worst_residual_percent, bounds::kResidualPercent);
  }
}

// The size's tilt term: a blob fit's size departing from the law by a share of its blur, bounded
// as the blob fit's blur corrections are.
void CheckTilt(Checker* c, const GeometricModel& g) {
  for (size_t i = 0; i < g.tilt_var_px2.size(); ++i) {
    c->Value("geometric.tilt_var_px2[" + std::to_string(i) + "]", g.tilt_var_px2[i],
             bounds::kBlurOffsetPx2);
  }
}

}  // namespace

std::vector<ModelBoundFailure> CheckModelBounds(const CalibrationModel& model) {
  Checker c;
  CheckBlur(&c, model.blur_calibration, model.ranges);
  CheckProvenance(&c, model.provenance, model.features);
  CheckFitness(&c, model.fitness);
  CheckTilt(&c, model.geometric);
  return c.Take();
}

}  // namespace irdist
