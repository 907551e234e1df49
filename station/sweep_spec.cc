#include "station/sweep_spec.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>

#include "base/check.h"

namespace irdist {
namespace {

bool Fail(std::string* why, const std::string& message) {
  if (why != nullptr) *why = message;
  return false;
}

bool AllFinite(const std::vector<double>& values) {
  return std::all_of(values.begin(), values.end(), [](double v) { return std::isfinite(v); });
}

bool AxisValid(const AxisValues& axis, const std::string& name, std::string* why) {
  if (axis.random.has_value()) {
    std::string inner;
    if (!axis.random->IsValid(&inner)) return Fail(why, name + ": " + inner);
    return true;
  }
  if (axis.values.empty()) return Fail(why, name + ": no values");
  if (!AllFinite(axis.values)) return Fail(why, name + ": values must be finite");
  return true;
}

// Frames of the whole sweep, in double: never overflows, whatever the counts.
double FrameCount(const SweepSpec& spec) {
  const double poses = static_cast<double>(spec.slide_mm.Count()) * spec.angle_deg.Count() *
                       spec.tilt_deg.Count() * spec.bias_ma.Count() * spec.bracket.repeats;
  return poses * static_cast<double>(PlannedExposures(spec.bracket).size());
}

}  // namespace

const AxisValues& AxisOf(const SweepSpec& spec, SweepAxis axis) {
  switch (axis) {
    case SweepAxis::kSlide:
      return spec.slide_mm;
    case SweepAxis::kAngle:
      return spec.angle_deg;
    case SweepAxis::kTilt:
      return spec.tilt_deg;
    case SweepAxis::kBias:
      return spec.bias_ma;
  }
  IRDIST_CHECK(false, "unknown SweepAxis");
}

std::string SweepAxisName(SweepAxis axis, AngleMode angle_mode) {
  switch (axis) {
    case SweepAxis::kSlide:
      return "slide_mm";
    case SweepAxis::kAngle:
      return angle_mode == AngleMode::kTheta ? "theta_deg" : "pan_deg";
    case SweepAxis::kTilt:
      return "tilt_deg";
    case SweepAxis::kBias:
      return "bias_ma";
  }
  return "?";
}

bool RandomDraws::IsValid(std::string* why) const {
  if (!std::isfinite(mean)) return Fail(why, "mean must be finite");
  if (!(sd >= 0.0) || !std::isfinite(sd)) return Fail(why, "sd must be >= 0");
  if (count < 1) return Fail(why, "count must be >= 1");
  if (!(min < max)) return Fail(why, "min must be < max");
  if (!(mean >= min && mean <= max)) return Fail(why, "mean must lie in [min, max]");
  if (!(AcceptedFraction() >= kMinAcceptedFraction)) {
    char text[200];
    std::snprintf(text, sizeof(text),
                  "only %.3g of the draws fall inside [min, max] (at least %g needed); lower sd "
                  "to at most %.6g or widen [min, max]",
                  AcceptedFraction(), kMinAcceptedFraction, LargestUsableSd());
    return Fail(why, text);
  }
  return true;
}

double RandomDraws::AcceptedFraction() const {
  if (sd == 0.0) return mean >= min && mean <= max ? 1.0 : 0.0;
  // Phi((max - mean) / sd) - Phi((min - mean) / sd), as a sum of two erf: no cancellation while
  // the mean lies inside the window.
  const double below = (mean - min) / sd;
  const double above = (max - mean) / sd;
  return 0.5 * (std::erf(above / std::sqrt(2.0)) + std::erf(below / std::sqrt(2.0)));
}

double RandomDraws::LargestUsableSd() const {
  RandomDraws probe = *this;
  probe.sd = std::numeric_limits<double>::max();
  if (probe.AcceptedFraction() >= kMinAcceptedFraction) return probe.sd;
  // AcceptedFraction() falls as sd grows: bisect log(sd) between 1e-300 and the largest double.
  double log_lo = std::log(1e-300), log_hi = std::log(probe.sd);
  for (int i = 0; i < 200; ++i) {
    const double log_mid = 0.5 * (log_lo + log_hi);
    probe.sd = std::exp(log_mid);
    (probe.AcceptedFraction() >= kMinAcceptedFraction ? log_lo : log_hi) = log_mid;
  }
  return std::exp(log_lo);
}

int AxisValues::Count() const {
  return random.has_value() ? random->count : static_cast<int>(values.size());
}

bool BracketSpec::IsValid(std::string* why) const {
  const std::string at_most = std::to_string(static_cast<long>(kMaxExposureMs)) + " ms";
  if (!(t_ref_ms > 0.0 && t_ref_ms <= kMaxExposureMs)) {
    return Fail(why, "t_ref_ms must lie in (0, " + at_most + "]");
  }
  if (t_meas_ms.empty()) return Fail(why, "t_meas_ms must hold at least one exposure");
  for (double t : t_meas_ms) {
    if (!(t > t_ref_ms && t <= kMaxExposureMs)) {
      return Fail(why, "every t_meas_ms must be greater than t_ref_ms and at most " + at_most);
    }
  }
  if (repeats < 1) return Fail(why, "repeats must be >= 1");
  return true;
}

bool SettleSpec::IsValid(std::string* why) const {
  if (!(after_move_ms >= 0.0 && after_move_ms <= kMaxSettleMs)) {
    return Fail(why, "after_move_ms must lie in [0, 3600000] ms (1 h)");
  }
  if (!(after_current_ms >= 0.0 && after_current_ms <= kMaxSettleMs)) {
    return Fail(why, "after_current_ms must lie in [0, 3600000] ms (1 h)");
  }
  return true;
}

bool SweepSpec::IsValid(std::string* why) const {
  const std::array<SweepAxis, 4> all = {SweepAxis::kSlide, SweepAxis::kAngle, SweepAxis::kTilt,
                                        SweepAxis::kBias};
  for (SweepAxis axis : all) {
    if (!AxisValid(AxisOf(*this, axis), SweepAxisName(axis, angle_mode), why)) return false;
  }
  for (const AxisValues* axis : {&angle_deg, &tilt_deg}) {
    for (double v : axis->values) {
      if (!(std::abs(v) < 90.0)) return Fail(why, "angles must lie in (-90, 90) deg");
    }
    // Random angles are drawn inside their window: it must lie inside the angles too (a draw of
    // -1.4e9 deg of tilt made a pan of NaN and a plan of NaN seconds).
    if (axis->random && !(axis->random->min > -90.0 && axis->random->max < 90.0)) {
      return Fail(why, "random angles need min and max inside (-90, 90) deg");
    }
  }
  if (!order.empty()) {
    if (order.size() != all.size()) return Fail(why, "order must name each of the 4 axes once");
    for (SweepAxis axis : all) {
      if (std::count(order.begin(), order.end(), axis) != 1) {
        return Fail(why, "order must name each of the 4 axes once");
      }
    }
  }
  for (SweepAxis axis : serpentine) {
    if (std::count(serpentine.begin(), serpentine.end(), axis) != 1) {
      return Fail(why, "serpentine names an axis twice");
    }
  }
  std::string inner;
  if (!bracket.IsValid(&inner)) return Fail(why, "bracket: " + inner);
  if (!settle.IsValid(&inner)) return Fail(why, "settle: " + inner);
  const double frames = FrameCount(*this);
  if (!(frames <= kMaxPlanFrames)) {
    char text[160];
    std::snprintf(text, sizeof(text), "the sweep has %.6g frames; at most %.6g (use fewer values, "
                  "repeats or exposures)", frames, kMaxPlanFrames);
    return Fail(why, text);
  }
  return true;
}

std::vector<PlannedExposure> PlannedExposures(const BracketSpec& bracket) {
  std::vector<PlannedExposure> frames;
  auto add = [&frames](double exposure_ms, bool is_reference, int reference_index) {
    PlannedExposure frame;
    frame.index = static_cast<int>(frames.size());
    frame.exposure_ms = exposure_ms;
    frame.is_reference = is_reference;
    frame.reference_index = reference_index;
    frames.push_back(frame);
    return frame.index;
  };
  int reference = -1;
  for (size_t n = 0; n < bracket.t_meas_ms.size(); ++n) {
    if (n == 0 || bracket.retake_reference) reference = add(bracket.t_ref_ms, true, -1);
    add(bracket.t_meas_ms[n], false, reference);
  }
  return frames;
}

}  // namespace irdist
