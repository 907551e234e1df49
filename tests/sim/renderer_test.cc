#include "sim/renderer.h"

#include <cmath>

#include <gtest/gtest.h>

namespace irdist::sim {
namespace {

struct Measured {
  double sum = 0.0;    // background-subtracted gray-level sum over the box
  double sigma = 0.0;  // its standard deviation, estimated from the frame itself
};

// Sums the box around the image centre and subtracts the background, estimated (mean and
// variance) from a band of pixels far from the emitter. Variance of the sum: K times the signal
// (shot noise) plus the box's pixel count times the background variance.
Measured SignalSum(const cv::Mat& frame, double gain_dn_per_e) {
  const cv::Rect box(640 - 40, 512 - 40, 80, 80);
  const cv::Rect band(0, 0, 1280, 200);
  cv::Mat f, bg;
  frame(box).convertTo(f, CV_64F);
  frame(band).convertTo(bg, CV_64F);
  cv::Scalar bg_mean, bg_sd;
  cv::meanStdDev(bg, bg_mean, bg_sd);
  Measured m;
  m.sum = cv::sum(f)[0] - bg_mean[0] * box.area();
  const double var = gain_dn_per_e * std::max(m.sum, 0.0) + box.area() * bg_sd[0] * bg_sd[0] +
                     std::pow(box.area(), 2) * bg_sd[0] * bg_sd[0] / band.area();
  m.sigma = std::sqrt(var);
  return m;
}

// Expects a / b == ratio within 5 standard deviations of the ratio (from the frames' noise).
void ExpectRatio(const Measured& a, const Measured& b, double ratio, const std::string& what) {
  const double r = a.sum / b.sum;
  const double sigma = r * std::hypot(a.sigma / a.sum, b.sigma / b.sum);
  EXPECT_NEAR(r, ratio, 5.0 * sigma) << what << ": measured " << r << " +- " << sigma;
  EXPECT_LT(sigma, 0.02 * ratio) << what << ": the test is too noisy to mean anything";
}

class RendererTest : public ::testing::Test {
 protected:
  RigPhysics physics_;
  Renderer renderer_{physics_};
  double k_ = physics_.sensor.system_gain_dn_per_e;
  std::uint64_t frame_ = 1;
  Measured Shot(double d, double pan, double bias, double exposure_s) {
    return SignalSum(renderer_.Render(StaticConditions(d, pan, 0, bias, exposure_s), frame_++,
                                      PixelFormat::kMono12),
                     k_);
  }
};

TEST_F(RendererTest, SignalFallsAsInverseSquareOfDistance) {
  const Measured near = Shot(1500, 0, 500, 0.03);
  for (double d : {2000.0, 2500.0, 3000.0}) {
    ExpectRatio(Shot(d, 0, 500, 0.03), near, std::pow(1500.0 / d, 2), "d " + std::to_string(d));
  }
}

TEST_F(RendererTest, SignalIsLinearInExposure) {
  const Measured ref = Shot(2000, 10, 500, 0.008);
  for (double t : {0.016, 0.030, 0.036}) {
    ExpectRatio(Shot(2000, 10, 500, t), ref, t / 0.008, "t " + std::to_string(t));
  }
}

TEST_F(RendererTest, SignalIsLinearInCurrentAboveThreshold) {
  const double th = physics_.emitter.threshold_ma;
  const Measured ref = Shot(2500, 20, 475, 0.03);
  for (double i : {300.0, 500.0, 550.0}) {
    ExpectRatio(Shot(2500, 20, i, 0.03), ref, (i - th) / (475 - th), "i " + std::to_string(i));
  }
  const Measured off = Shot(2500, 20, th * 0.5, 0.03);
  EXPECT_NEAR(off.sum, 0.0, 5 * off.sigma);
}

TEST_F(RendererTest, GroundTruthPeakMatchesRenderedFrames) {
  // Average 16 frames' brightest 3x3 neighbourhood against the noise-free peak.
  PoseState pose;
  pose.slide_mm = 1500;
  pose.bias_ma = 500;
  const GroundTruth truth = renderer_.Describe(pose, 0.03, PixelFormat::kMono12);
  cv::Mat acc = cv::Mat::zeros(1024, 1280, CV_64F);
  for (int n = 0; n < 16; ++n) {
    cv::Mat f;
    renderer_.Render(StaticConditions(1500, 0, 0, 500, 0.03), 100 + n, PixelFormat::kMono12)
        .convertTo(f, CV_64F);
    acc += f / 16.0;
  }
  double hi;
  cv::minMaxLoc(acc, nullptr, &hi);
  EXPECT_NEAR(hi, truth.peak_gray, 0.02 * truth.peak_gray) << truth.BriefReport();
  EXPECT_FALSE(truth.saturated);
}

// The defaults: resolved at 3 m, unsaturated at 1.5 m for 40 ms at 550 mA, and well
// above the noise at 3 m, 35 degrees, 8 ms, 450 mA.
TEST_F(RendererTest, DefaultsNeitherSaturateNorDrownOverTheWorkingRange) {
  PoseState near;
  near.slide_mm = 1500;
  near.bias_ma = 550;
  const GroundTruth bright = renderer_.Describe(near, 0.040, PixelFormat::kMono12);
  EXPECT_FALSE(bright.saturated) << bright.BriefReport();
  PoseState far;
  far.slide_mm = 3000;
  far.pan_deg = 35;
  far.bias_ma = 450;
  const GroundTruth dim = renderer_.Describe(far, 0.008, PixelFormat::kMono12);
  EXPECT_GE(dim.major_px, 8.0);
  const double noise_e = std::sqrt(dim.peak_signal_e + std::pow(physics_.sensor.read_noise_e, 2));
  EXPECT_GT(dim.peak_signal_e / noise_e, 20.0) << dim.BriefReport();
}

TEST_F(RendererTest, MovingExposureSmearsBetweenPoses) {
  FrameConditions c = StaticConditions(2000, 0, 0, 500, 0.02);
  c.pose_end.slide_mm = 2000;
  c.pose_end.pan_deg = 0;
  const SignalWindow still = renderer_.Signal(c);
  c.pose_start.moving = c.pose_end.moving = true;
  c.pose_end.pan_deg = 30;  // rotating during the exposure
  const SignalWindow moving = renderer_.Signal(c);
  const double ratio = cv::sum(moving.electrons)[0] / cv::sum(still.electrons)[0];
  EXPECT_NEAR(ratio, 0.5 * (1.0 + renderer_.scene().Pattern(30 * 3.14159265358979 / 180)), 0.01);
}

// The intensity-weighted width (2 sigma along x, px) and the sum of a signal window.
double WidthPx(const SignalWindow& w) {
  double sum = 0.0, sx = 0.0, sxx = 0.0;
  for (int r = 0; r < w.electrons.rows; ++r) {
    for (int c = 0; c < w.electrons.cols; ++c) {
      const double e = w.electrons(r, c), x = w.rect.x + c;
      sum += e;
      sx += e * x;
      sxx += e * x * x;
    }
  }
  return 2.0 * std::sqrt(sxx / sum - (sx / sum) * (sx / sum));
}

// docs/virtual-rig.md "Truth of a moving target": a slide cruising at 0.5 m/s through an 8 ms
// exposure (1498 -> 1502 mm), rendered in sub-steps along its profile, images at the size and
// signal of its mid-exposure pose (1500 mm), not of its start: the frame's truth is mid-exposure.
TEST_F(RendererTest, SlideMovingHalfAMetrePerSecondImagesAtItsMidExposurePose) {
  const double exposure_s = 0.008;
  const MotionProfile cruise = MotionProfile::Make(1498.0, 1700.0, 0.0, 500.0, 500.0, 1000.0);
  FrameConditions moving = StaticConditions(1498, 0, 0, 500, exposure_s);
  moving.pose_end.slide_mm = cruise.PositionAt(exposure_s);
  ASSERT_NEAR(moving.pose_end.slide_mm, 1502.0, 1e-9);
  for (int k = 0; k < 5; ++k) {
    PoseState pose = moving.pose_start;
    pose.slide_mm = cruise.PositionAt((k + 0.5) / 5 * exposure_s);
    moving.sub_steps.push_back(pose);
  }
  const SignalWindow smeared = renderer_.Signal(moving);
  const SignalWindow mid = renderer_.Signal(StaticConditions(1500, 0, 0, 500, exposure_s));
  const SignalWindow start = renderer_.Signal(StaticConditions(1498, 0, 0, 500, exposure_s));
  const double width_px = WidthPx(smeared);
  EXPECT_NEAR(width_px / WidthPx(mid), 1.0, 2e-5);
  EXPECT_NEAR(cv::sum(smeared.electrons)[0] / cv::sum(mid.electrons)[0], 1.0, 2e-5);
  // The start pose is 2 mm nearer: 0.13 % larger, which this comparison resolves.
  EXPECT_GT(WidthPx(start) / width_px - 1.0, 5e-4);
}

}  // namespace
}  // namespace irdist::sim
