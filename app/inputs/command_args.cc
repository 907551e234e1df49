#include "app/inputs/command_args.h"

#include <cmath>
#include <string>
#include <vector>

#include "app/inputs/errors.h"
#include "base/bounds.h"
#include "station/serial_transport.h"

namespace irdist {
namespace {

// Appends "; " and `text` to a non-empty *why (or sets it); returns false.
bool Refuse(std::string* why, const std::string& text) {
  if (why != nullptr) *why += (why->empty() ? "" : "; ") + text;
  return false;
}

// `value` inside `bound`, or 0 where 0 means "the default".
bool Bounded(const char* flag, const Bound& bound, double value, bool zero_is_default,
             std::string* why) {
  if (zero_is_default && value == 0.0) return true;
  const std::string refusal = bound.Refusal(flag, value);
  return refusal.empty() || Refuse(why, refusal);
}

bool TimeScale(double value, std::string* why) {
  if (value == 0.0 || bounds::kTimeScale.Contains(value)) return true;
  return Refuse(why, "--time-scale " + BoundNumber(value) + " is outside " +
                         BoundNumber(bounds::kTimeScale.min) + ".." +
                         BoundNumber(bounds::kTimeScale.max) +
                         " (simulated seconds per host second; 0 = the rig file's)");
}

// --at: none, or SLIDE_MM,PAN_DEG,TILT_DEG,BIAS_MA, each finite within 1e6 and the bias >= 0.
bool At(const std::vector<double>& at, std::string* why) {
  if (at.empty()) return true;
  if (at.size() != 4) {
    return Refuse(why, "--at takes 4 numbers (SLIDE_MM,PAN_DEG,TILT_DEG,BIAS_MA), not " +
                           std::to_string(at.size()));
  }
  for (double value : at) {
    if (!(std::fabs(value) <= kMaxAtValue)) {
      return Refuse(why, "--at " + BoundNumber(value) + " is outside [-" +
                             BoundNumber(kMaxAtValue) + ", " + BoundNumber(kMaxAtValue) + "]");
    }
  }
  return at[3] >= 0.0 || Refuse(why, "--at's BIAS_MA " + BoundNumber(at[3]) + " is negative");
}

}  // namespace

void RefuseArgs(const char* command, const std::string& why) {
  throw UsageError(std::string("irdist ") + command + ": " + why);
}

bool CalibrateArgs::IsValid(std::string* why) const { return TimeScale(time_scale, why); }

bool ValidateArgs::IsValid(std::string* why) const { return TimeScale(time_scale, why); }

bool MeasureArgs::IsValid(std::string* why) const {
  bool ok = Bounded("--t-ref-ms", bounds::kExposureMs, t_ref_ms, true, why);
  for (double t_ms : t_meas_ms) {
    ok = Bounded("--t-meas-ms", bounds::kExposureMs, t_ms, false, why) && ok;
  }
  ok = Bounded("--count", bounds::kCount, count, true, why) && ok;
  ok = Bounded("--duration", bounds::kDurationS, duration_s, true, why) && ok;
  ok = Bounded("--max-disk-gb", bounds::kDiskGb, max_disk_gb, true, why) && ok;
  ok = Bounded("--exposure-ms", bounds::kExposureMs, exposure_ms, true, why) && ok;
  ok = Bounded("--accel-psd", bounds::kAccelPsd, accel_psd_mm2_per_s3, true, why) && ok;
  ok = Bounded("--check-every", bounds::kDurationS, check_every_s, true, why) && ok;
  ok = At(at, why) && ok;
  return TimeScale(time_scale, why) && ok;
}

bool SnapArgs::IsValid(std::string* why) const {
  const bool ok = Bounded("--exposure-ms", bounds::kExposureMs, exposure_ms, false, why);
  return At(at, why) && TimeScale(time_scale, why) && ok;
}

bool ViewArgs::IsValid(std::string* why) const {
  bool ok = Bounded("--exposure-ms", bounds::kExposureMs, exposure_ms, false, why);
  ok = Bounded("--frames", bounds::kCount, frames, true, why) && ok;
  return At(at, why) && TimeScale(time_scale, why) && ok;
}

bool PlanArgs::IsValid(std::string* why) const {
  bool ok = TimeScale(time_scale, why);
  if (show_poses < -1 || show_poses > kMaxShownPoses) {
    ok = Refuse(why, "--poses " + std::to_string(show_poses) + " is outside -1.." +
                         std::to_string(kMaxShownPoses));
  }
  return ok;
}

bool SimArgs::IsValid(std::string* why) const { return TimeScale(time_scale, why); }

bool StationArgs::IsValid(std::string* why) const {
  for (double value : values) {
    if (!std::isfinite(value)) return Refuse(why, "station " + action + ": a value is not finite");
  }
  return true;
}

bool StationTestArgs::IsValid(std::string* why) const {
  if (baud >= 1 && static_cast<unsigned int>(baud) <= kMaxBaud) return true;
  return Refuse(why, "--baud " + std::to_string(baud) + " is outside [1, " +
                         std::to_string(kMaxBaud) + "] bit/s");
}

}  // namespace irdist
