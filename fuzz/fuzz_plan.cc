// libFuzzer target: station/plan.h's MakePlan on a SweepSpec and MotionModel made from the input's
// bytes (FuzzedDataProvider): lists and random draws on every axis with any numbers, any axis order,
// any bracket, settle and motion. A spec that IsValid() refuses is skipped; a valid one must plan
// in bounded time and memory (libFuzzer's -timeout and -rss_limit_mb) or be refused with an
// irdist::Error. Anything else (another exception, a sanitizer report) is a finding.
#include <fuzzer/FuzzedDataProvider.h>

#include <cstddef>
#include <cstdint>
#include <string>

#include "base/bounds.h"
#include "base/check.h"
#include "station/plan.h"

namespace {

double AnyNumber(FuzzedDataProvider& in) {
  switch (in.ConsumeIntegralInRange<int>(0, 3)) {
    case 0: return in.ConsumeFloatingPoint<double>();  // any double, huge ones included
    case 1: return in.ConsumeFloatingPointInRange<double>(-10.0, 10.0);
    case 2: return in.ConsumeFloatingPointInRange<double>(0.0, 4000.0);
    default: return static_cast<double>(in.ConsumeIntegral<std::int32_t>());
  }
}

irdist::AxisValues AnyAxis(FuzzedDataProvider& in) {
  irdist::AxisValues axis;
  if (in.ConsumeBool()) {
    irdist::RandomDraws draws;
    draws.mean = AnyNumber(in);
    draws.sd = AnyNumber(in);
    draws.count = in.ConsumeIntegralInRange<int>(-2, 1 << 20);
    draws.seed = in.ConsumeIntegral<std::uint64_t>();
    draws.per_pose = in.ConsumeBool();
    draws.min = in.ConsumeBool() ? -1e300 : AnyNumber(in);
    draws.max = in.ConsumeBool() ? 1e300 : AnyNumber(in);
    axis.random = draws;
    return axis;
  }
  const int count = in.ConsumeIntegralInRange<int>(0, 64);
  for (int i = 0; i < count; ++i) axis.values.push_back(AnyNumber(in));
  return axis;
}

irdist::AxisMotion AnyAxisMotion(FuzzedDataProvider& in) {
  return {AnyNumber(in), AnyNumber(in), AnyNumber(in), AnyNumber(in)};
}

irdist::SweepSpec AnySpec(FuzzedDataProvider& in) {
  irdist::SweepSpec spec;
  spec.slide_mm = AnyAxis(in);
  spec.angle_deg = AnyAxis(in);
  spec.tilt_deg = AnyAxis(in);
  spec.bias_ma = AnyAxis(in);
  spec.angle_mode = in.ConsumeBool() ? irdist::AngleMode::kTheta : irdist::AngleMode::kPan;
  const int order = in.ConsumeIntegralInRange<int>(0, 5);
  for (int i = 0; i < order; ++i) {
    spec.order.push_back(static_cast<irdist::SweepAxis>(in.ConsumeIntegralInRange<int>(0, 3)));
  }
  spec.bracket.t_ref_ms = AnyNumber(in);
  spec.bracket.t_meas_ms.clear();
  const int frames = in.ConsumeIntegralInRange<int>(0, 12);
  for (int i = 0; i < frames; ++i) spec.bracket.t_meas_ms.push_back(AnyNumber(in));
  spec.bracket.repeats = in.ConsumeIntegralInRange<int>(-1, 1 << 16);
  spec.bracket.retake_reference = in.ConsumeBool();
  spec.settle.after_move_ms = AnyNumber(in);
  spec.settle.after_current_ms = AnyNumber(in);
  return spec;
}

irdist::MotionModel AnyMotion(FuzzedDataProvider& in) {
  irdist::MotionModel motion;
  if (in.ConsumeBool()) return motion;  // the defaults: most inputs then reach the planner
  motion.slide = AnyAxisMotion(in);
  motion.pan = AnyAxisMotion(in);
  motion.tilt = AnyAxisMotion(in);
  motion.axes_move_together = in.ConsumeBool();
  motion.readout_ms = AnyNumber(in);
  motion.frame_overhead_ms = AnyNumber(in);
  motion.pose_overhead_ms = AnyNumber(in);
  return motion;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  FuzzedDataProvider in(data, size);
  const irdist::SweepSpec spec = AnySpec(in);
  const irdist::MotionModel motion = AnyMotion(in);
  std::string why;
  if (!spec.IsValid(&why) || !motion.IsValid(&why)) return 0;
  // Accepted implies in the table (base/bounds.h): the bracket's exposures.
  if (!irdist::bounds::kExposureMs.Contains(spec.bracket.t_ref_ms)) __builtin_trap();
  for (double t_ms : spec.bracket.t_meas_ms) {
    if (!irdist::bounds::kExposureMs.Contains(t_ms)) __builtin_trap();
  }
  try {
    const irdist::Plan plan = irdist::MakePlan(spec, motion);
    if (plan.summary.frame_count < 0 || !(plan.summary.total_s >= 0.0)) __builtin_trap();
    irdist::FormatDuration(plan.summary.total_s);
  } catch (const irdist::Error&) {
    // a refusal (e.g. a theta the tilt cannot reach): fine
  }
  return 0;
}
