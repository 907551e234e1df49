#include "estimator/disc_fit.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "tests/estimator/scene_render.h"

namespace irdist {
namespace {

using testing::RenderScene;
using testing::SceneDisc;
using testing::SensorFrame;

constexpr int kSide = 64;
constexpr double kMaxGray = 4095.0;
// SensorFrame's black level (DN) and gain (DN per electron).
constexpr double kBlackDn = 16.0;
constexpr double kGainDn = 0.39;

// A noise-free Mono12 frame of one disc (the independent renderer: 16 x 16 sub-samples per pixel,
// an exact ellipse, a Gaussian blur on the fine grid).
cv::Mat DiscFrame(const SceneDisc& disc, double blur_px) {
  return SensorFrame(RenderScene(kSide, 0.0, {disc}, blur_px), cv::Mat1d());
}

// The background-subtracted centroid and second moments over `rect`, as FitDisc starts from.
DiscMoments MomentsOf(const cv::Mat& image, const cv::Rect& rect) {
  double s = 0.0, sx = 0.0, sy = 0.0;
  for (int y = rect.y; y < rect.br().y; ++y) {
    for (int x = rect.x; x < rect.br().x; ++x) {
      const double w = image.at<std::uint16_t>(y, x) - kBlackDn;
      s += w;
      sx += w * x;
      sy += w * y;
    }
  }
  DiscMoments m;
  m.cx = sx / s;
  m.cy = sy / s;
  for (int y = rect.y; y < rect.br().y; ++y) {
    for (int x = rect.x; x < rect.br().x; ++x) {
      const double w = image.at<std::uint16_t>(y, x) - kBlackDn;
      m.sxx += w * (x - m.cx) * (x - m.cx) / s;
      m.syy += w * (y - m.cy) * (y - m.cy) / s;
      m.sxy += w * (x - m.cx) * (y - m.cy) / s;
    }
  }
  return m;
}

struct DiscResult {
  bool ok = false;
  EllipseFit fit;
  double blur_px = -1.0;
  double rms = -1.0;
};

DiscResult Fit(const cv::Mat& image, const cv::Rect& rect, const EllipseFit& contour = {}) {
  DiscResult r;
  const double peak = kBlackDn + kGainDn * 8000.0;
  r.ok = FitDisc(image, rect, kMaxGray, MomentsOf(image, rect), contour, kBlackDn, peak, 0.7,
                 &r.fit, &r.blur_px, &r.rms);
  return r;
}

double AngleError(double a_deg, double b_deg) {
  const double e = std::fmod(std::abs(a_deg - b_deg), 180.0);
  return std::min(e, 180.0 - e);
}

TEST(Theta0FromAxes, IsTheTiltOfACircleSeenObliquely) {
  // A circle tilted by theta shows minor / major = cos(theta).
  EXPECT_NEAR(Theta0FromAxes(5.0, 10.0), 60.0, 1e-12);
  EXPECT_NEAR(Theta0FromAxes(std::sqrt(0.5), 1.0), 45.0, 1e-12);
  EXPECT_EQ(Theta0FromAxes(7.0, 7.0), 0.0);
  EXPECT_NEAR(Theta0FromAxes(0.0, 7.0), 90.0, 1e-12);
  // Out of range: the ratio is clamped to [0, 1]; a degenerate ellipse has no tilt.
  EXPECT_EQ(Theta0FromAxes(8.0, 7.0), 0.0);
  EXPECT_NEAR(Theta0FromAxes(-1.0, 7.0), 90.0, 1e-12);
  EXPECT_EQ(Theta0FromAxes(3.0, 0.0), 0.0);
  EXPECT_EQ(Theta0FromAxes(3.0, -2.0), 0.0);
}

// A round disc of radius 7 px blurred by 0.7 px: the fitted ellipse is that circle, centred where
// it was drawn, and the fitted blur is the drawn one.
TEST(FitDisc, RecoversARoundBlurredDisc) {
  SceneDisc disc;
  disc.cx = 31.3;
  disc.cy = 32.6;
  disc.a = disc.b = 7.0;
  disc.amplitude_e = 8000.0;
  const cv::Mat image = DiscFrame(disc, 0.7);
  const DiscResult r = Fit(image, cv::Rect(20, 21, 23, 23));
  ASSERT_TRUE(r.ok);
  EXPECT_TRUE(r.fit.valid);
  EXPECT_NEAR(r.fit.major_px, 14.0, 0.1);
  EXPECT_NEAR(r.fit.minor_px, 14.0, 0.1);
  EXPECT_NEAR(r.fit.center_px.x, 31.3, 0.03);
  EXPECT_NEAR(r.fit.center_px.y, 32.6, 0.03);
  EXPECT_NEAR(r.blur_px, 0.7, 0.1);
  EXPECT_LT(r.fit.theta0_deg, 10.0);
  // A good fit leaves residuals well below 1 % of the plateau (normalised gray levels).
  EXPECT_LT(r.rms, 0.01 * kGainDn * 8000.0 / kMaxGray);
}

// An ellipse 16 x 10 px at 30 deg: its axes, direction and tilt acos(10 / 16) = 51.3 deg.
TEST(FitDisc, RecoversATiltedEllipse) {
  SceneDisc disc;
  disc.cx = 32.2;
  disc.cy = 31.7;
  disc.a = 8.0;
  disc.b = 5.0;
  disc.angle_deg = 30.0;
  disc.amplitude_e = 8000.0;
  const cv::Mat image = DiscFrame(disc, 0.6);
  const DiscResult r = Fit(image, cv::Rect(20, 20, 25, 25));
  ASSERT_TRUE(r.ok);
  EXPECT_NEAR(r.fit.major_px, 16.0, 0.1);
  EXPECT_NEAR(r.fit.minor_px, 10.0, 0.1);
  EXPECT_LT(AngleError(r.fit.angle_deg, 30.0), 1.0) << r.fit.angle_deg;
  EXPECT_NEAR(r.fit.theta0_deg, std::acos(10.0 / 16.0) * 180.0 / M_PI, 1.0);
  EXPECT_NEAR(r.blur_px, 0.6, 0.1);
  EXPECT_NEAR(r.fit.center_px.x, 32.2, 0.03);
  EXPECT_NEAR(r.fit.center_px.y, 31.7, 0.03);
}

// The same ellipse turned to -45 deg, started from a (slightly wrong) half-maximum contour
// instead of the moments: the fit still lands on the drawn ellipse.
TEST(FitDisc, StartsFromTheContourWhenItHasOne) {
  SceneDisc disc;
  disc.cx = 32.0;
  disc.cy = 32.0;
  disc.a = 8.0;
  disc.b = 6.0;
  disc.angle_deg = -45.0;
  disc.amplitude_e = 8000.0;
  const cv::Mat image = DiscFrame(disc, 0.8);
  EllipseFit contour;
  contour.valid = true;
  contour.center_px = cv::Point2d(32.0, 32.0);
  contour.major_px = 15.0;
  contour.minor_px = 12.5;
  contour.angle_deg = -40.0;
  const DiscResult r = Fit(image, cv::Rect(19, 19, 27, 27), contour);
  ASSERT_TRUE(r.ok);
  EXPECT_NEAR(r.fit.major_px, 16.0, 0.1);
  EXPECT_NEAR(r.fit.minor_px, 12.0, 0.1);
  EXPECT_LT(AngleError(r.fit.angle_deg, -45.0), 1.5) << r.fit.angle_deg;
  EXPECT_GE(r.fit.angle_deg, -90.0);
  EXPECT_LE(r.fit.angle_deg, 90.0);
  EXPECT_NEAR(r.blur_px, 0.8, 0.1);
}

// Fewer pixels than four per parameter (8 parameters: 32 pixels) are no fit; the outputs are left
// as they were.
TEST(FitDisc, RefusesTooFewPixels) {
  SceneDisc disc;
  disc.cx = disc.cy = 32.0;
  disc.a = disc.b = 2.0;
  disc.amplitude_e = 8000.0;
  const cv::Mat image = DiscFrame(disc, 0.7);
  DiscResult r;
  r.ok = FitDisc(image, cv::Rect(29, 29, 5, 6), kMaxGray, MomentsOf(image, cv::Rect(29, 29, 5, 6)),
                 EllipseFit(), kBlackDn, kBlackDn + 3000.0, 0.7, &r.fit, &r.blur_px, &r.rms);
  EXPECT_FALSE(r.ok);
  EXPECT_FALSE(r.fit.valid);
  EXPECT_EQ(r.blur_px, -1.0);
  EXPECT_EQ(r.rms, -1.0);
}

}  // namespace
}  // namespace irdist
