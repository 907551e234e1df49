#include "base/bounds.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

namespace irdist {
namespace {

TEST(Bounds, NonFiniteNumbersAreNeverInside) {
  for (const Bound& b : {bounds::kExposureMs, bounds::kDurationS, bounds::kShare}) {
    SCOPED_TRACE(b.name);
    EXPECT_FALSE(b.Contains(std::nan("")));
    EXPECT_FALSE(b.Contains(std::numeric_limits<double>::infinity()));
    EXPECT_FALSE(b.Contains(-std::numeric_limits<double>::infinity()));
  }
}

TEST(Bounds, OpenAndClosedEnds) {
  EXPECT_FALSE(bounds::kDurationS.Contains(0.0));  // (0, a day]
  EXPECT_TRUE(bounds::kDurationS.Contains(1e-9));
  EXPECT_TRUE(bounds::kDurationS.Contains(86400.0));
  EXPECT_FALSE(bounds::kDurationS.Contains(86400.001));
  EXPECT_TRUE(bounds::kShare.Contains(0.0));  // [0, 1]
  EXPECT_TRUE(bounds::kShare.Contains(1.0));
  EXPECT_FALSE(bounds::kCount.Contains(0.0));
}

// A refusal names the value, the range in plain numbers, the quantity, its physics and the fix.
TEST(Bounds, ARefusalSaysRangeAndWhyInPlainNumbers) {
  EXPECT_EQ(bounds::kDurationS.Refusal("--duration", 60.0), "");
  const std::string refusal = bounds::kDurationS.Refusal("reset_wait_s", 1e308, "give seconds");
  EXPECT_EQ(refusal,
            "reset_wait_s = 1e+308 is outside (0, 86400] s (duration or wait: a run's duration or "
            "a device's wait lies within a day); give seconds");
  EXPECT_EQ(bounds::kShare.RangeText(), "[0, 1]");
}

TEST(Bounds, EveryBoundIsAFiniteRangeWithItsReason) {
  for (const Bound& b :
       {bounds::kExposureMs, bounds::kDurationS, bounds::kDelayMs, bounds::kDiskGb, bounds::kCount,
        bounds::kToleranceSteps,
        bounds::kSensorPx, bounds::kBitDepth, bounds::kFrameBitDepth, bounds::kFocalPx,
        bounds::kRadialDistortion, bounds::kTangentialDistortion, bounds::kBlurVarPx2,
        bounds::kBlurOffsetPx2, bounds::kBlurNoisePx2, bounds::kNoiseExponent, bounds::kShare,
        bounds::kChiSquare, bounds::kTailProbability, bounds::kResidualPercent,
        bounds::kSlideSpeedMmS, bounds::kAngularSpeedDegS, bounds::kPositionSdMm}) {
    SCOPED_TRACE(b.name);
    EXPECT_TRUE(std::isfinite(b.min) && std::isfinite(b.max));
    EXPECT_LT(b.min, b.max);
    EXPECT_GT(std::string(b.why).size(), 10u);
  }
}

}  // namespace
}  // namespace irdist
