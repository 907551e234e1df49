// One frame's estimate for `measure --track` (docs/measure.md "Tracking"): the distance through the
// calibration's geometric size model (the disc's image variance falls as 1/d^2), theta from the
// disc's axis ratio with the blur removed (cos theta = minor / major axis), a standard error that
// falls as 1/sqrt(exposure), the frame's exposure in the range checks and the position along the
// blob's ray. The live session around it is tested in track_session_test.cc.
#include "app/live/track_estimate.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "base/pi.h"

namespace irdist {
namespace {

constexpr double kDeg = kPi / 180.0;
constexpr double kAlphaPx2 = 16.0;  // the disc's major-axis variance at 1 m: 16 px^2
constexpr double kBlurPx2 = 0.5;    // the calibrated blur, per axis

// A calibration over 1500-3000 mm and 0-60 deg, reference 8 ms, measurement exposures 20-40 ms
// (mean 30 ms), the size's relative noise 1e-3 at 1 m growing linearly with d.
CalibrationModel Model() {
  CalibrationModel model;
  GeometricModel& g = model.geometric;
  g.alpha_px2 = kAlphaPx2;
  g.beta_px2 = kBlurPx2;
  g.noise_rel_at_1m = 1e-3;
  g.noise_exponent = 1.0;
  g.summary.mean_relative_error = 0.01;
  model.provenance.t_ref_ms = 8.0;
  model.provenance.t_meas_ms = {20.0, 30.0, 40.0};
  CalibratedRanges& r = model.ranges;
  r.d_min_mm = 1500.0;
  r.d_max_mm = 3000.0;
  r.theta_min_deg = 0.0;
  r.theta_max_deg = 60.0;
  r.t_ref_min_ms = r.t_ref_max_ms = 8.0;
  r.t_min_ms = 20.0;
  r.t_max_ms = 40.0;
  r.bias_min_ma = 400.0;
  r.bias_max_ma = 600.0;
  return model;
}

// The features of a disc at d_mm turned by theta_deg: its image's major-axis variance
// alpha (1 m / d)^2, the minor axis's cos^2(theta) of it, each with the blur added (the blob
// fit's calibrated blur, which it names), centred at `centroid` in the frame's own pixels.
Features Disc(double d_mm, double theta_deg, cv::Point2d centroid = {100.25, 80.5}) {
  Features f;
  f.blob_found = true;
  f.peak = 0.6;
  f.centroid_px = centroid;
  const double major = kAlphaPx2 * 1e6 / (d_mm * d_mm);
  const double cos_theta = std::cos(theta_deg * kDeg);
  f.moment_major_var_px2 = major + kBlurPx2;
  f.moment_minor_var_px2 = major * cos_theta * cos_theta + kBlurPx2;
  f.size_blur_var_px2 = kBlurPx2;
  f.theta0_deg = 90.0;  // a wrong value: the estimate must not take the features' own theta
  return f;
}

CameraGeometry NoIntrinsics() {
  CameraGeometry g;
  g.roi_offset_x = 500;
  g.roi_offset_y = 400;
  return g;
}

// A pinhole camera (f = 2000 px, no distortion) with its principal point at (640, 512) on the
// sensor.
CameraGeometry Pinhole() {
  CameraGeometry g = NoIntrinsics();
  g.intrinsics.known = true;
  g.intrinsics.fx_px = g.intrinsics.fy_px = 2000.0;
  g.intrinsics.cx_px = 640.0;
  g.intrinsics.cy_px = 512.0;
  return g;
}

bool Contains(const std::vector<std::string>& names, const std::string& name) {
  for (const std::string& n : names) {
    if (n == name) return true;
  }
  return false;
}

// sd(d) = 1e-3 (d / 1 m) d at the calibration's mean exposure (30 ms): 4 mm at 2 m; a size's
// noise falls as 1/sqrt(signal), so 4x the exposure halves it and a quarter doubles it.
TEST(FrameDistanceSeMm, CalibratedNoiseScaledByTheSquareRootOfTheExposure) {
  const CalibrationModel model = Model();
  EXPECT_NEAR(FrameDistanceSeMm(model, 2000.0, 30.0), 4.0, 1e-9);
  EXPECT_NEAR(FrameDistanceSeMm(model, 2000.0, 120.0), 2.0, 1e-9);
  EXPECT_NEAR(FrameDistanceSeMm(model, 2000.0, 7.5), 8.0, 1e-9);
  EXPECT_NEAR(FrameDistanceSeMm(model, 3000.0, 30.0), 9.0, 1e-9);  // 3e-3 x 3000 mm
}

// A model without the noise law leans on the geometric fit's mean relative error (1% of d at the
// calibration's exposure); a model with neither has no standard error.
TEST(FrameDistanceSeMm, WithoutTheNoiseLawTheFitsMeanErrorAndWithNeitherNone) {
  CalibrationModel model = Model();
  model.geometric.noise_rel_at_1m = 0.0;
  EXPECT_NEAR(FrameDistanceSeMm(model, 2000.0, 30.0), 20.0, 1e-9);
  model.geometric.summary.mean_relative_error = -1.0;
  EXPECT_TRUE(std::isnan(FrameDistanceSeMm(model, 2000.0, 30.0)));
}

TEST(EstimateFrame, ReadsDistanceFromTheSizeAndThetaFromTheAxisRatio) {
  const MeasureSample s = EstimateFrame(Disc(2000.0, 30.0), 30.0, Model(), NoIntrinsics(), 17);
  EXPECT_EQ(s.bracket, 17);
  ASSERT_TRUE(s.have_estimate);
  ASSERT_TRUE(s.estimate.ok);
  EXPECT_NEAR(s.estimate.d_mm, 2000.0, 1e-6);
  EXPECT_NEAR(s.estimate.theta_deg, 30.0, 1e-6);
  EXPECT_NEAR(s.estimate.d_std_mm, 4.0, 1e-6);
  EXPECT_TRUE(std::isnan(s.estimate.theta_std_deg));  // no calibrated theta correction
  EXPECT_TRUE(s.estimate.outside.empty());
  // The blob in the whole sensor's pixels: the frame's centroid plus the ROI's offset.
  EXPECT_DOUBLE_EQ(s.blob_x_px, 600.25);
  EXPECT_DOUBLE_EQ(s.blob_y_px, 480.5);
  EXPECT_FALSE(s.has_position);  // no intrinsics, no 3D
}

// theta's standard error is the calibrated correction's scatter: the sd of a normal law whose mean
// absolute residual is 0.4 deg, sqrt(pi / 2) x 0.4 = 0.501 deg.
TEST(EstimateFrame, ThetaStandardErrorIsTheCorrectionsCalibrationScatter) {
  CalibrationModel model = Model();
  model.theta_correction.degree = 1;
  model.theta_correction.coefficients = {0.0, 1.0, 0.0};  // cos^2 theta = x
  model.theta_correction.ratio_sq_max = 1.0;
  model.theta_correction.d_min_mm = 1500.0;
  model.theta_correction.d_max_mm = 3000.0;
  model.theta_correction.summary.mean_relative_error = 0.4;
  const MeasureSample s = EstimateFrame(Disc(2000.0, 30.0), 30.0, model, NoIntrinsics(), 0);
  ASSERT_TRUE(s.estimate.ok);
  EXPECT_NEAR(s.estimate.theta_std_deg, 0.5013, 1e-4);
}

// A frame without a usable blob is a sample without an estimate, its problems named, never an
// exception: the stream of per-frame lines goes on.
TEST(EstimateFrame, AnUnusableFrameGivesASampleWithoutAnEstimate) {
  Features saturated = Disc(2000.0, 30.0);
  saturated.saturated_pixels = 3;
  MeasureSample s = EstimateFrame(saturated, 30.0, Model(), NoIntrinsics(), 1);
  EXPECT_TRUE(s.have_estimate);
  EXPECT_FALSE(s.estimate.ok);
  EXPECT_TRUE(s.saturated);
  EXPECT_TRUE(std::isnan(s.estimate.d_mm));
  EXPECT_NE(QualityFlags(s).find("no_estimate"), std::string::npos) << QualityFlags(s);

  Features none;
  s = EstimateFrame(none, 30.0, Model(), Pinhole(), 2);
  EXPECT_FALSE(s.estimate.ok);
  EXPECT_FALSE(s.blob_found);
  EXPECT_FALSE(s.has_position);
  EXPECT_NE(QualityFlags(s).find("no_blob"), std::string::npos) << QualityFlags(s);
}

// The frame's exposure is the one checked against the calibration: the reference (8 ms) and a
// measurement exposure inside 20-40 ms are inside, 50 ms is outside as a measurement exposure;
// a disc at 4 m (4 mm se: well beyond 3 se of the 3 m edge) is outside the distances.
TEST(EstimateFrame, TheFramesExposureAndDistanceAreCheckedAgainstTheCalibration) {
  const CalibrationModel model = Model();
  for (double exposure_ms : {8.0, 25.0}) {
    const MeasureSample s =
        EstimateFrame(Disc(2000.0, 30.0), exposure_ms, model, NoIntrinsics(), 0);
    EXPECT_FALSE(s.estimate.outside_range) << exposure_ms << " ms";
  }
  MeasureSample s = EstimateFrame(Disc(2000.0, 30.0), 50.0, model, NoIntrinsics(), 0);
  EXPECT_TRUE(s.estimate.outside_range);
  EXPECT_TRUE(Contains(s.estimate.outside, "t_meas")) << JoinNames(s.estimate.outside, " ");
  EXPECT_FALSE(Contains(s.estimate.outside, "t_ref"));
  s = EstimateFrame(Disc(4000.0, 30.0), 30.0, model, NoIntrinsics(), 0);
  ASSERT_TRUE(s.estimate.ok);
  EXPECT_NEAR(s.estimate.d_mm, 4000.0, 1e-6);
  EXPECT_TRUE(Contains(s.estimate.outside, "distance")) << JoinNames(s.estimate.outside, " ");
}

// With intrinsics the IRED lies on the blob's ray at the estimated range: on the optical axis
// straight ahead (z = d, its se the range's; one frame has no centre scatter, so x and y have
// none), off it along the ray (x / z = (u - cx) / fx).
TEST(EstimateFrame, ThePositionLiesOnTheBlobsRayAtTheEstimatedRange) {
  const CameraGeometry g = Pinhole();
  // (140, 112) in the frame + the ROI's (500, 400) = the principal point.
  MeasureSample s = EstimateFrame(Disc(2000.0, 20.0, {140.0, 112.0}), 30.0, Model(), g, 0);
  ASSERT_TRUE(s.has_position);
  EXPECT_NEAR(s.z_mm, 2000.0, 1e-3);
  EXPECT_NEAR(s.x_mm, 0.0, 1e-6);
  EXPECT_NEAR(s.y_mm, 0.0, 1e-6);
  EXPECT_NEAR(s.z_se_mm, 4.0, 1e-3);
  EXPECT_TRUE(std::isnan(s.x_se_mm));
  EXPECT_TRUE(std::isnan(s.y_se_mm));

  // 200 px right of the principal point: the ray at atan(0.1) from the axis.
  s = EstimateFrame(Disc(2000.0, 20.0, {340.0, 112.0}), 30.0, Model(), g, 0);
  ASSERT_TRUE(s.has_position);
  EXPECT_NEAR(s.x_mm / s.z_mm, 0.1, 1e-6);
  EXPECT_NEAR(s.y_mm, 0.0, 1e-6);
  EXPECT_NEAR(std::hypot(s.x_mm, s.y_mm, s.z_mm), s.estimate.d_mm, 1e-6);
}

}  // namespace
}  // namespace irdist
