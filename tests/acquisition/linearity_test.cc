// Tests of acquisition/linearity.h: the EMVA 1288 linearity error of a straight line, a gamma
// curve and a saturated top, and the exposure series on a synthetic camera (a lit blob, a LUT,
// no light).
#include "acquisition/linearity.h"

#include <gtest/gtest.h>

#include <cmath>

namespace irdist {
namespace {

constexpr double kFullScale = 4095.0;
constexpr double kDark = 60.0;

// The points of a response `dn(t)` at six exposures.
std::vector<LinearityPoint> Series(const std::function<double(double)>& dn) {
  std::vector<LinearityPoint> points;
  for (double t : {1000.0, 4000.0, 7000.0, 10000.0, 13000.0, 16000.0}) points.push_back({t, dn(t)});
  return points;
}

TEST(FitLinearity, AStraightLineHasNoError) {
  const LinearityResult r =
      FitLinearity(kDark, kFullScale, Series([](double t) { return kDark + 0.22 * t; }), {});
  ASSERT_TRUE(r.measured) << r.why;
  EXPECT_LT(r.error_percent, 1e-9);
  EXPECT_NEAR(r.slope_dn_per_us, 0.22, 1e-12);
  EXPECT_NEAR(r.intercept_dn, kDark, 1e-9);
  EXPECT_TRUE(r.Passed());
  EXPECT_EQ(r.points_used, 6);
}

TEST(FitLinearity, AGammaCurveFailsTheLimit) {
  const auto gamma = [](double t) {
    return kDark + (kFullScale - kDark) * std::pow(t / 17000.0, 0.45);
  };
  const LinearityResult r = FitLinearity(kDark, kFullScale, Series(gamma), {});
  ASSERT_TRUE(r.measured) << r.why;
  EXPECT_GT(r.error_percent, 5.0);
  EXPECT_FALSE(r.Passed());
  EXPECT_NE(r.BriefReport().find("linearity error"), std::string::npos);
}

TEST(FitLinearity, ASaturatedTopIsLeftOutOfTheFit) {
  const auto clipped = [](double t) { return std::min(kFullScale, kDark + 0.3 * t); };
  const LinearityResult r = FitLinearity(kDark, kFullScale, Series(clipped), {});
  ASSERT_TRUE(r.measured) << r.why;
  EXPECT_EQ(r.points_saturated, 2);  // 13000 and 16000 us clip at 4095
  EXPECT_EQ(r.points_used, 4);
  EXPECT_LT(r.error_percent, 1e-9);
  EXPECT_NE(r.BriefReport().find("saturated left out"), std::string::npos);
}

TEST(FitLinearity, SmallDeviationsAreMeasuredInPercentOfTheRange) {
  // One point 10 DN off a line rising 3300 DN over the series: about 0.3% of the range.
  std::vector<LinearityPoint> points = Series([](double t) { return kDark + 0.22 * t; });
  points[3].mean_dn += 10.0;
  const LinearityResult r = FitLinearity(kDark, kFullScale, points, {});
  ASSERT_TRUE(r.measured);
  EXPECT_GT(r.error_percent, 0.15);
  EXPECT_LT(r.error_percent, 0.35);
}

TEST(FitLinearity, NoLightIsSaidNotMeasured) {
  const LinearityResult r =
      FitLinearity(kDark, kFullScale, Series([](double t) { return kDark + 1e-4 * t; }), {});
  EXPECT_FALSE(r.measured);
  EXPECT_FALSE(r.Passed());
  EXPECT_EQ(r.why.rfind("no light", 0), 0u) << r.why;
}

// A synthetic camera: a Gaussian blob whose gray levels grow with the exposure through `curve`;
// step_us > 0: it takes the exposure rounded to whole steps (and says so), as a FLIR's whole
// microseconds.
GrabAt BlobCamera(double rate_dn_per_us, const std::function<double(double)>& curve,
                  double step_us = 0.0) {
  return [rate_dn_per_us, curve, step_us](double asked_us) -> std::optional<ExposedFrame> {
    const double exposure_us =
        step_us > 0.0 ? std::max(step_us, step_us * std::round(asked_us / step_us)) : asked_us;
    cv::Mat image(64, 64, CV_16UC1);
    for (int y = 0; y < 64; ++y) {
      for (int x = 0; x < 64; ++x) {
        const double r2 = (x - 40) * (x - 40) + (y - 20) * (y - 20);
        const double linear = kDark + rate_dn_per_us * exposure_us * std::exp(-r2 / 200.0);
        image.at<std::uint16_t>(y, x) =
            static_cast<std::uint16_t>(std::lround(std::min(kFullScale, curve(linear))));
      }
    }
    return ExposedFrame{image, exposure_us};
  };
}

// The dark frame of a synthetic camera: its shortest exposure's image.
std::function<std::optional<cv::Mat>()> DarkOf(const GrabAt& grab) {
  return [grab]() -> std::optional<cv::Mat> { return grab(0.0)->image; };
}

TEST(MeasureLinearity, ALinearCameraPassesWithTheDarkOffset) {
  const GrabAt grab = BlobCamera(0.5, [](double v) { return v; });
  const LinearityResult r =
      MeasureLinearity(grab, DarkOf(grab), 50000.0, 10.0, 1e6, kFullScale, {});
  ASSERT_TRUE(r.measured) << r.why;
  EXPECT_LT(r.error_percent, 0.3);  // integer rounding only
  EXPECT_NEAR(r.dark_dn, kDark, 0.5);
  EXPECT_EQ(r.points.size(), 6u);
  EXPECT_EQ(r.points_saturated, 0);
}

// A bright source on a camera whose exposure is whole microseconds: the series' exposures are
// 1.6 to 14 us asked, up to 25% off once rounded; each window is measured at the exposure the
// camera took, so the line stays straight (the asked exposures would read a few % nonlinear).
TEST(MeasureLinearity, ACameraThatRoundsTheExposureIsMeasuredAtWhatItTook) {
  const GrabAt grab = BlobCamera(200.0, [](double v) { return v; }, 1.0);
  const LinearityResult r = MeasureLinearity(grab, DarkOf(grab), 5.0, 1.0, 1e6, kFullScale, {});
  ASSERT_TRUE(r.measured) << r.why;
  EXPECT_LT(r.error_percent, 0.3) << "points measured at the asked exposures, not the taken ones";
  for (const LinearityPoint& p : r.points) {
    EXPECT_EQ(p.exposure_us, std::round(p.exposure_us)) << "an exposure the camera never took";
  }
}

TEST(MeasureLinearity, ALutCurveFails) {
  const auto lut = [](double v) { return kFullScale * std::pow(v / kFullScale, 0.45); };
  const GrabAt grab = BlobCamera(0.5, lut);
  const LinearityResult r =
      MeasureLinearity(grab, DarkOf(grab), 1000.0, 10.0, 1e6, kFullScale, {});
  ASSERT_TRUE(r.measured) << r.why;
  EXPECT_GT(r.error_percent, 1.0);
  EXPECT_FALSE(r.Passed());
}

TEST(MeasureLinearity, ADarkSceneSaysSo) {
  const GrabAt grab = BlobCamera(0.0, [](double v) { return v; });
  const LinearityResult r =
      MeasureLinearity(grab, DarkOf(grab), 1000.0, 10.0, 20000.0, kFullScale, {});
  EXPECT_FALSE(r.measured);
  EXPECT_EQ(r.why.rfind("no light", 0), 0u) << r.why;
}

}  // namespace
}  // namespace irdist
