#include "estimator/features.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <string>
#include <opencv2/imgproc.hpp>

#include "base/check.h"
#include "base/pi.h"
#include "sim/renderer.h"
#include "sim/rig_physics.h"
#include "tests/estimator/disc_spectrum.h"

namespace irdist {
namespace {

struct Blob {
  double cx = 640.0, cy = 512.0;
  double diameter_px = 30.0;  // major axis
  double theta_deg = 0.0;     // minor = major * cos(theta)
  double angle_deg = 30.0;    // orientation of the major axis in the image
  double blur_sigma_px = 1.0;
  double level = 0.5;  // plateau above background, fraction of full scale
  double background = 0.02;
};

// Renders a uniformly bright ellipse (8x supersampled, area-averaged, Gaussian-blurred) into a
// CV_16UC1 frame with bit_depth content.
cv::Mat Render(const Blob& b, int bit_depth, cv::Size size = cv::Size(1280, 1024)) {
  const double max_gray = (1 << bit_depth) - 1;
  const int ss = 8;
  const int half = static_cast<int>(b.diameter_px) + 12;
  const int side = 2 * half;
  const double ox = std::floor(b.cx) - half, oy = std::floor(b.cy) - half;
  cv::Mat fine = cv::Mat::zeros(side * ss, side * ss, CV_32F);
  const int shift = 8;
  const double scale = ss * (1 << shift);
  cv::ellipse(
      fine,
      cv::Point(static_cast<int>(std::lround((b.cx - ox) * scale + 0.5 * (ss - 1) * (1 << shift))),
                static_cast<int>(std::lround((b.cy - oy) * scale + 0.5 * (ss - 1) * (1 << shift)))),
      cv::Size(static_cast<int>(std::lround(0.5 * b.diameter_px * scale)),
               static_cast<int>(
                   std::lround(0.5 * b.diameter_px * std::cos(b.theta_deg * kPi / 180.0) * scale))),
      b.angle_deg, 0, 360, cv::Scalar(1.0), cv::FILLED, cv::LINE_8, shift);
  cv::Mat patch;
  cv::resize(fine, patch, cv::Size(side, side), 0, 0, cv::INTER_AREA);
  if (b.blur_sigma_px > 0) cv::GaussianBlur(patch, patch, cv::Size(0, 0), b.blur_sigma_px);
  cv::Mat frame(size, CV_32F, cv::Scalar(b.background));
  cv::Rect target(static_cast<int>(ox), static_cast<int>(oy), side, side);
  cv::Rect clipped = target & cv::Rect(0, 0, size.width, size.height);
  cv::Mat dst = frame(clipped);
  cv::Mat src =
      patch(cv::Rect(clipped.x - target.x, clipped.y - target.y, clipped.width, clipped.height));
  dst += src * b.level;
  cv::Mat out;
  frame.convertTo(out, CV_16U, max_gray);  // saturates at 65535; clip to the format below
  cv::min(out, cv::Scalar(max_gray), out);
  return out;
}

TEST(FeatureOptions, DefaultsAreValid) {
  std::string why;
  EXPECT_TRUE(FeatureOptions().IsValid(&why)) << why;
  FeatureOptions bad;
  bad.window_side_px = 2;
  EXPECT_FALSE(bad.IsValid(&why));
  bad = FeatureOptions();
  bad.inverse_response.m = {0.0, 0.5, 0.4};
  bad.inverse_response.f = {0.0, 0.5, 1.0};
  EXPECT_FALSE(bad.IsValid(&why));
  EXPECT_NE(why.find("increase"), std::string::npos);
}

TEST(FeatureOptions, MomentMethodNamesRoundTrip) {
  for (MomentMethod m : {MomentMethod::kThreshold, MomentMethod::kAperture}) {
    MomentMethod parsed = m == MomentMethod::kThreshold ? MomentMethod::kAperture
                                                        : MomentMethod::kThreshold;
    EXPECT_TRUE(ParseMomentMethod(ToString(m), &parsed));
    EXPECT_EQ(parsed, m);
  }
  MomentMethod m;
  EXPECT_FALSE(ParseMomentMethod("gaussian", &m));
  FeatureOptions bad;
  bad.aperture_margin_px = -1.0;
  std::string why;
  EXPECT_FALSE(bad.IsValid(&why));
}

// Aperture moments keep the blob's whole profile: the variances of profile and blur add, so going
// from one blur to another changes both axes' variances by exactly the difference of the blurs'
// variances; the threshold cuts the wider blur's wings and sees less of it.
TEST(Features, ApertureMomentsAddTheWholeBlurVariance) {
  Features aperture_f[2], threshold_f[2];
  const double blurs[2] = {0.7, 1.5};
  for (int k = 0; k < 2; ++k) {
    Blob b;
    b.diameter_px = 16.0;
    b.theta_deg = 25.0;
    b.blur_sigma_px = blurs[k];
    b.cx = 640.37;
    b.cy = 512.81;
    const cv::Mat image = Render(b, 12);
    FeatureOptions aperture;
    aperture.moment_method = MomentMethod::kAperture;
    aperture_f[k] = ComputeFeatures(image, 12, aperture);
    FeatureOptions threshold;
    threshold.moment_method = MomentMethod::kThreshold;
    threshold_f[k] = ComputeFeatures(image, 12, threshold);
    ASSERT_TRUE(aperture_f[k].blob_found && threshold_f[k].blob_found);
    EXPECT_NEAR(aperture_f[k].centroid_px.x, b.cx, 0.05);
  }
  const double expected = blurs[1] * blurs[1] - blurs[0] * blurs[0];
  const double major = aperture_f[1].moment_major_var_px2 - aperture_f[0].moment_major_var_px2;
  const double minor = aperture_f[1].moment_minor_var_px2 - aperture_f[0].moment_minor_var_px2;
  EXPECT_NEAR(major, expected, 0.02 * expected);
  EXPECT_NEAR(minor, expected, 0.02 * expected);
  const double threshold_major =
      threshold_f[1].moment_major_var_px2 - threshold_f[0].moment_major_var_px2;
  EXPECT_LT(threshold_major, major - 0.05 * expected);
}

// A dim blob (peak about 100 read-noise sd, the 8 ms reference of a far, tilted pose): 2% of the
// contrast is within the noise, so noise pixels anywhere in the window passed the moments'
// threshold and the farthest of them set the aperture (minor variance 0.3 px^2 for about 7). The
// threshold now stays 5 noise sd above the background: the variances are the blob's.
TEST(Features, ADimBlobsMomentsAreTheBlobsNotTheNoises) {
  Blob b;
  b.diameter_px = 11.0;
  b.theta_deg = 30.0;
  b.blur_sigma_px = 1.0;
  b.level = 0.10;  // 410 gray levels
  b.background = 0.004;
  const cv::Mat clean = Render(b, 12);
  cv::Mat noise(clean.size(), CV_32F);
  cv::Mat noisy;
  clean.convertTo(noisy, CV_32F);
  cv::RNG rng(17);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, 4.0);  // 4 gray levels of read noise
  noisy += noise;
  cv::Mat frame;
  noisy.convertTo(frame, CV_16U);
  const Features f = ComputeFeatures(frame, 12, FeatureOptions());
  ASSERT_TRUE(f.Usable()) << f.BriefReport();
  const Features truth = ComputeFeatures(clean, 12, FeatureOptions());
  EXPECT_NEAR(f.moment_major_var_px2 / truth.moment_major_var_px2, 1.0, 0.1);
  EXPECT_NEAR(f.moment_minor_var_px2 / truth.moment_minor_var_px2, 1.0, 0.1);
}

TEST(FeatureOptions, EllipseMethodNamesRoundTrip) {
  for (EllipseMethod m :
       {EllipseMethod::kMoments, EllipseMethod::kContour, EllipseMethod::kModelFit}) {
    EllipseMethod parsed = m == EllipseMethod::kMoments ? EllipseMethod::kContour
                                                        : EllipseMethod::kMoments;
    EXPECT_TRUE(ParseEllipseMethod(ToString(m), &parsed));
    EXPECT_EQ(parsed, m);
  }
  EllipseMethod m;
  EXPECT_FALSE(ParseEllipseMethod("gaussian", &m));
}

// The disc model integrated over the pixels recovers small blurred ellipses' axes, where the moment
// ellipse (blur and pixel variance removed) is biased by the pixel grid; the fitted blur is the
// rendering's.
TEST(Features, ModelFitBeatsMomentsOnSmallBlurredEllipses) {
  const double blur = 0.7;
  FeatureOptions model;
  model.ellipse_method = EllipseMethod::kModelFit;
  FeatureOptions moments;
  moments.psf_sigma_px = std::sqrt(blur * blur + 1.0 / 12.0);  // blur and pixel area removed
  double worst_model = 0.0, worst_moments = 0.0, sum_model = 0.0, sum_moments = 0.0;
  int n = 0;
  for (double diameter : {8.0, 10.0, 12.0}) {
    for (double theta : {15.0, 20.0, 30.0}) {
      for (double angle : {0.0, 35.0, 90.0}) {
        Blob b;
        b.diameter_px = diameter;
        b.theta_deg = theta;
        b.angle_deg = angle;
        b.blur_sigma_px = blur;
        b.level = 0.6;
        b.cx = 600.0 + 0.13 * n;
        b.cy = 400.0 + 0.29 * n;
        const cv::Mat image = Render(b, 12);
        const Features f = ComputeFeatures(image, 12, model);
        const Features g = ComputeFeatures(image, 12, moments);
        ASSERT_TRUE(f.blob_found && g.blob_found);
        ASSERT_TRUE(f.ellipse_model.valid) << "d=" << diameter << " theta=" << theta;
        EXPECT_EQ(f.theta0_deg, f.ellipse_model.theta0_deg);
        EXPECT_FALSE(g.ellipse_model.valid);
        const double minor = diameter * std::cos(theta * kPi / 180.0);
        // The polygon rasterised on the 8x grid is ~1/8 px wider than the ellipse it draws.
        EXPECT_NEAR(f.ellipse_model.major_px, diameter + 0.1, 0.1);
        EXPECT_NEAR(f.ellipse_model.minor_px, minor + 0.1, 0.1);
        EXPECT_NEAR(f.model_blur_px, blur, 0.15);
        EXPECT_NEAR(f.ellipse_model.center_px.x, b.cx, 0.05);
        EXPECT_NEAR(f.ellipse_model.center_px.y, b.cy, 0.05);
        double angle_error = std::fmod(std::abs(f.ellipse_model.angle_deg - angle), 180.0);
        angle_error = std::min(angle_error, 180.0 - angle_error);
        // The orientation of a nearly round 8 px blob is weakly determined.
        EXPECT_LT(angle_error, diameter >= 10.0 ? 3.0 : 6.0) << "d=" << diameter;
        const double em = std::abs(f.theta0_deg - theta);
        const double eg = std::abs(g.ellipse_moments.theta0_deg - theta);
        // The rendering's own truth is good to ~1/16 px (8x supersampled polygon): ~1 deg of
        // theta at 15 deg on an 8 px blob.
        EXPECT_LT(em, diameter >= 10.0 ? 1.0 : 1.5)
            << "d=" << diameter << " theta=" << theta << " angle=" << angle;
        worst_model = std::max(worst_model, em);
        worst_moments = std::max(worst_moments, eg);
        sum_model += em;
        sum_moments += eg;
        ++n;
      }
    }
  }
  EXPECT_LT(sum_model, 0.9 * sum_moments);
  std::printf("small blobs, theta0 error (deg) model fit: mean %.3f max %.3f; moments: mean %.3f "
              "max %.3f\n",
              sum_model / n, worst_model, sum_moments / n, worst_moments);
}

TEST(Features, F00EqualsDftDcTermOfRoi) {
  Blob b;
  const cv::Mat image = Render(b, 12);
  const Features f = ComputeFeatures(image, 12, PaperFeatureOptions());
  ASSERT_TRUE(f.blob_found);
  cv::Mat roi;
  image(f.roi).convertTo(roi, CV_64F);
  cv::Mat spectrum;
  cv::dft(roi, spectrum, cv::DFT_COMPLEX_OUTPUT);
  const cv::Vec2d dc = spectrum.at<cv::Vec2d>(0, 0);
  EXPECT_NEAR(f.f00, dc[0] / 4095.0, 1e-9 * f.f00);
  EXPECT_NEAR(dc[1], 0.0, 1e-6);
  // The default takes the window's background off: the DC term less the window's area times it.
  const Features d = ComputeFeatures(image, 12, FeatureOptions());
  EXPECT_GT(d.window_background, 0.0);
  EXPECT_NEAR(d.f00, dc[0] / 4095.0 - 64 * 64 * d.window_background, 1e-9 * d.f00);
  // Fixed window and identity response: E_rel = F(0,0) / A (NOTES.md: the E equation degenerates).
  EXPECT_EQ(f.roi_area_px, 64 * 64);
  EXPECT_NEAR(f.e_rel, f.f00 / f.roi_area_px, 1e-12);
  EXPECT_NEAR(d.e_rel, d.f00 / d.roi_area_px, 1e-12);
  EXPECT_GT(f.sigma, 0.0);
  EXPECT_NEAR(f.centroid_px.x, b.cx, 0.05);
  EXPECT_NEAR(f.centroid_px.y, b.cy, 0.05);
  EXPECT_TRUE(f.Usable()) << f.BriefReport();
}

TEST(Features, Theta0WithinOneDegreeOnRenderedEllipses) {
  FeatureOptions options;
  options.psf_sigma_px = 1.0;  // the rendering blur, known from the optics
  double worst_moments = 0.0, worst_contour = 0.0, sum_moments = 0.0, sum_contour = 0.0;
  int n = 0;
  for (double diameter : {20.0, 30.0, 40.0}) {
    for (double theta : {20.0, 30.0, 40.0, 50.0}) {
      for (double angle : {0.0, 35.0, 90.0}) {
        Blob b;
        b.diameter_px = diameter;
        b.theta_deg = theta;
        b.angle_deg = angle;
        b.cx = 600.3 + 0.1 * n;
        b.cy = 400.7;
        const Features f = ComputeFeatures(Render(b, 12), 12, options);
        ASSERT_TRUE(f.blob_found);
        ASSERT_TRUE(f.ellipse_moments.valid && f.ellipse_contour.valid);
        const double em = std::abs(f.ellipse_moments.theta0_deg - theta);
        const double ec = std::abs(f.ellipse_contour.theta0_deg - theta);
        EXPECT_LT(em, 1.0) << "d=" << diameter << " theta=" << theta << " angle=" << angle;
        EXPECT_EQ(f.theta0_deg, f.ellipse_moments.theta0_deg);
        worst_moments = std::max(worst_moments, em);
        worst_contour = std::max(worst_contour, ec);
        sum_moments += em;
        sum_contour += ec;
        ++n;
      }
    }
  }
  // The default (moments) must be the better of the two on these blobs.
  EXPECT_LE(sum_moments, sum_contour);
  RecordProperty("mean_theta_error_moments_deg", std::to_string(sum_moments / n));
  RecordProperty("mean_theta_error_contour_deg", std::to_string(sum_contour / n));
  RecordProperty("max_theta_error_moments_deg", std::to_string(worst_moments));
  RecordProperty("max_theta_error_contour_deg", std::to_string(worst_contour));
  std::printf("theta0 error (deg) moments: mean %.3f max %.3f; contour: mean %.3f max %.3f\n",
              sum_moments / n, worst_moments, sum_contour / n, worst_contour);
}

TEST(Features, SaturationIsCountedNotHidden) {
  Blob b;
  b.level = 0.5;
  EXPECT_EQ(ComputeFeatures(Render(b, 12), 12, FeatureOptions()).saturated_pixels, 0);
  b.level = 3.0;  // plateau far above full scale: clipped
  const Features f = ComputeFeatures(Render(b, 12), 12, FeatureOptions());
  EXPECT_TRUE(f.blob_found);
  EXPECT_GT(f.saturated_pixels, 100);
  EXPECT_FALSE(f.Usable());
  EXPECT_NE(f.BriefReport().find("SATURATED"), std::string::npos);
}

TEST(Features, BorderAndNoBlobFlags) {
  Blob b;
  b.cx = 8.0;
  b.cy = 300.0;
  const Features edge = ComputeFeatures(Render(b, 12), 12, FeatureOptions());
  ASSERT_TRUE(edge.blob_found);
  EXPECT_TRUE(edge.touches_border);
  EXPECT_FALSE(edge.Usable());

  Blob big;
  big.diameter_px = 80.0;  // larger than the 64 px window
  const Features clipped = ComputeFeatures(Render(big, 12), 12, FeatureOptions());
  EXPECT_TRUE(clipped.blob_clipped_by_roi);

  cv::Mat flat(1024, 1280, CV_16UC1, cv::Scalar(100));
  cv::RNG rng(1);
  cv::Mat noise(flat.size(), CV_16UC1);
  rng.fill(noise, cv::RNG::UNIFORM, 0, 8);
  flat += noise;
  const Features none = ComputeFeatures(flat, 12, FeatureOptions());
  EXPECT_FALSE(none.blob_found);
  EXPECT_EQ(none.BriefReport(), "no blob found");
}

TEST(Features, BitDepthNormalisationAndInverseResponse) {
  Blob b;
  const Features f12 = ComputeFeatures(Render(b, 12), 12, FeatureOptions());
  const Features f16 = ComputeFeatures(Render(b, 16), 16, FeatureOptions());
  const Features f8 = ComputeFeatures(Render(b, 8), 8, FeatureOptions());
  EXPECT_NEAR(f12.f00, f16.f00, 2e-3 * f16.f00);
  EXPECT_NEAR(f8.f00, f16.f00, 2e-2 * f16.f00);
  EXPECT_NEAR(f12.sigma, f16.sigma, 2e-3 * f16.sigma);

  FeatureOptions squared;
  squared.inverse_response.m = {0.0, 0.5, 1.0};
  squared.inverse_response.f = {0.0, 0.25, 1.0};
  const Features fs = ComputeFeatures(Render(b, 12), 12, squared);
  EXPECT_DOUBLE_EQ(fs.f00, f12.f00);  // F(0,0) is of gray levels, not of f
  EXPECT_LT(fs.e_rel, f12.e_rel);     // f(m) <= m on this curve
  EXPECT_DOUBLE_EQ(squared.inverse_response.Apply(0.75), 0.625);
}

TEST(Features, ThresholdRoiFollowsTheBlob) {
  FeatureOptions options;
  options.roi_policy = RoiPolicy::kThreshold;
  Blob small, large;
  small.diameter_px = 20.0;
  large.diameter_px = 40.0;
  const Features fs = ComputeFeatures(Render(small, 12), 12, options);
  const Features fl = ComputeFeatures(Render(large, 12), 12, options);
  ASSERT_TRUE(fs.blob_found && fl.blob_found);
  const double expected_ratio = 4.0;  // area grows as diameter^2
  EXPECT_NEAR(static_cast<double>(fl.roi_area_px) / fs.roi_area_px, expected_ratio, 0.6);
  // Threshold ROI: E_rel is the mean over blob pixels, no longer F / 64^2.
  EXPECT_NEAR(fl.e_rel, fl.f00 / fl.roi_area_px, 1e-12);
  EXPECT_GT(fl.e_rel, 0.3);
}

TEST(Features, RejectsWrongType) {
  cv::Mat wrong(100, 100, CV_8UC1, cv::Scalar(0));
  EXPECT_THROW(ComputeFeatures(wrong, 8, FeatureOptions()), CheckError);
  cv::Mat right(100, 100, CV_16UC1, cv::Scalar(0));
  EXPECT_THROW(ComputeFeatures(right, 17, FeatureOptions()), CheckError);
}

}  // namespace
}  // namespace irdist

// ResponseScope::kAllPixels: the frame of a nonlinear sensor (sim/sensor.cc: ADC value x becomes
// x - a x^2 / x_max), linearised with the sensor's true inverse, gives the linear sensor's features.
namespace irdist {
namespace {

TEST(FeatureOptions, ResponseScopeNamesRoundTrip) {
  for (ResponseScope s : {ResponseScope::kERelOnly, ResponseScope::kAllPixels}) {
    ResponseScope back = ResponseScope::kERelOnly;
    ASSERT_TRUE(ParseResponseScope(ToString(s), &back));
    EXPECT_EQ(back, s);
  }
  ResponseScope back;
  EXPECT_FALSE(ParseResponseScope("everything", &back));
  EXPECT_EQ(FeatureOptions().response_scope, ResponseScope::kERelOnly);
}

// The linear ADC value x(M) that the nonlinear sensor (x - a x^2 / x_max) reads as the normalised
// gray level M, from the sensor's formula.
double LinearAdcValue(double m, double a, double x_max) {
  return x_max * (1.0 - std::sqrt(1.0 - 4.0 * a * m)) / (2.0 * a);
}

// The nonlinear sensor's inverse on normalised gray levels, x(M) / x_max, at 257 knots.
InverseResponse NonlinearSensorInverse(double a, double x_max) {
  InverseResponse truth;
  for (int k = 0; k <= 256; ++k) {
    truth.m.push_back(k / 256.0);
    truth.f.push_back(LinearAdcValue(k / 256.0, a, x_max) / x_max);
  }
  return truth;
}

TEST(Features, AllPixelsScopeLinearisesEveryFeature) {
  const double a = 0.1, x_max = 4095.0;
  sim::RigPhysics physics =
      sim::LoadRigPhysics(std::string(IRDIST_SOURCE_DIR) + "/recipes/rigs/virtual.yaml");
  const sim::Renderer linear_renderer(physics);
  physics.sensor.nonlinearity = a;
  const sim::Renderer nonlinear_renderer(physics);
  // LineariseFrame maps to L = f / f(1) (f(0) = 0 here): the linear frame's gray levels times
  // x_max / x(1).
  const double scale = x_max / LinearAdcValue(1.0, a, x_max);
  FeatureOptions all;
  all.inverse_response = NonlinearSensorInverse(a, x_max);
  all.response_scope = ResponseScope::kAllPixels;
  FeatureOptions e_only = all;
  e_only.response_scope = ResponseScope::kERelOnly;
  const int side = 160;
  const cv::Point origin(physics.sensor.width_px / 2 - side / 2,
                         physics.sensor.height_px / 2 - side / 2);
  std::uint64_t frame_index = 0;
  for (double d_mm : {1500.0, 2700.0}) {
    for (double theta_deg : {0.0, 30.0}) {
      const sim::FrameConditions c = sim::StaticConditions(d_mm, theta_deg, 0.0, 500.0, 0.035);
      cv::Mat linear(side, side, CV_16UC1), nonlinear(side, side, CV_16UC1);
      ++frame_index;  // the same noise draws for both sensors
      linear_renderer.Render(c, frame_index, sim::PixelFormat::kMono12, origin, linear);
      nonlinear_renderer.Render(c, frame_index, sim::PixelFormat::kMono12, origin, nonlinear);
      const Features ref = ComputeFeatures(linear, 12, FeatureOptions());
      const Features lin = ComputeFeatures(nonlinear, 12, all);
      const Features raw = ComputeFeatures(nonlinear, 12, e_only);
      SCOPED_TRACE(ref.BriefReport() + " | " + lin.BriefReport());
      ASSERT_TRUE(ref.Usable() && lin.Usable());
      EXPECT_EQ(lin.bit_depth, 12);
      // Second moments (the geometric size) and F(0,0): within 0.2 % (rounding of the nonlinear
      // ADC value is the only difference); the raw nonlinear frame misses F by several %.
      EXPECT_NEAR(lin.moment_major_var_px2 / ref.moment_major_var_px2, 1.0, 0.002);
      EXPECT_NEAR(lin.moment_minor_var_px2 / ref.moment_minor_var_px2, 1.0, 0.002);
      EXPECT_NEAR(lin.f00 / (ref.f00 * scale), 1.0, 0.002);
      EXPECT_NEAR(lin.sigma / (ref.sigma * scale), 1.0, 0.002);
      EXPECT_NEAR(lin.centroid_px.x, ref.centroid_px.x, 0.01);
      EXPECT_GT(std::abs(raw.f00 / ref.f00 - 1.0), 0.02);
      // E_rel-only scope: f (here x / x_max, not rescaled) enters E only; F stays the raw one's.
      EXPECT_NEAR(raw.e_rel * raw.roi_area_px / ref.f00, 1.0, 0.002);
      EXPECT_NEAR(raw.f00 / lin.f00, ComputeFeatures(nonlinear, 12, FeatureOptions()).f00 / lin.f00,
                  1e-12);
    }
  }
  // A frame at full scale still counts as saturated after linearisation.
  cv::Mat flat(64, 64, CV_16UC1, cv::Scalar(100));
  flat(cv::Rect(28, 28, 8, 8)).setTo(4095);
  const Features sat = ComputeFeatures(flat, 12, all);
  ASSERT_TRUE(sat.blob_found);
  EXPECT_EQ(sat.saturated_pixels, 64);
}


// The size the geometric distance reads (the aperture moments' variance less the blur) must not
// depend on where the disc's edge falls inside a pixel, whatever the mix of blur before the pixels
// sample the image (optics) and after (crosstalk). Noise free, on an independent
// renderer (tests/estimator/disc_spectrum.h: the disc's exact spectrum, the optics' Gaussian, the
// pixel's square, the sampling's aliases, then a sampled Gaussian's crosstalk); the disc's radius
// swept over 5..6 px (the virtual rig's far end) in 0.05 px steps, centred on a pixel corner and
// off it. The background-subtracted second moment is the disc's plus the optics', the pixel's
// (1/12) and the crosstalk's variances, whatever their order: a discrete blur of the sampled image
// adds its variance exactly, and the optics' Gaussian band-limits what the pixels sample. Relative
// distance error (-1/2 of the variance's, d ~ 1 / size), peak to peak over the sweep:
// <= 0.05% with 0.7 and 1 px of optics (measured <= 0.004%); with 0.3 px the image before the
// pixels is not band-limited and the sampling itself aliases: 0.067-0.068% at every crosstalk
// (docs/estimator.md "The blob's size whatever the edge's phase"), asserted at its measured level.
TEST(Features, ApertureMomentsSizeDoesNotDependOnTheEdgesPhase) {
  for (double centre : {19.5, 19.2}) {
    for (double optics : {0.3, 0.7, 1.0}) {
      for (double crosstalk : {0.0, 0.6, 1.0}) {
        const double blur_var =
            optics * optics + 1.0 / 12.0 + testing::CrosstalkVariance(crosstalk);
        std::vector<double> error;
        for (int k = 0; k <= 20; ++k) {
          testing::DiscBlob blob;
          blob.cx = blob.cy = centre;
          blob.a = blob.b = 5.0 + 0.05 * k;
          blob.optics_sigma_px = optics;
          blob.crosstalk_sigma_px = crosstalk;
          const cv::Mat frame =
              testing::DiscFrame16(testing::RenderDiscSpectrum(blob, 40), 50000.0, 1000.0);
          FeatureOptions options;
          options.window_side_px = 32;
          const Features f = ComputeFeatures(frame, 16, options);
          ASSERT_TRUE(f.Usable());
          const double var = 0.5 * (f.moment_major_var_px2 + f.moment_minor_var_px2) - blur_var;
          error.push_back(-0.5 * (var / (blob.a * blob.a / 4.0) - 1.0));
        }
        const double limit = optics < 0.5 ? 8e-4 : 5e-4;
        EXPECT_LT(testing::PeakToPeak(error), limit)
            << "optics " << optics << " px, crosstalk " << crosstalk << " px, centre " << centre;
      }
    }
  }
}

}  // namespace
}  // namespace irdist

namespace irdist {
namespace {

// Ambient light proportional to the exposure, with a gradient across the frame, adds to every
// pixel: taken off by the window's background, E_rel and F(0,0) are the IRED's light alone (what
// the clean frame gives), while the paper's features carry the ambient's whole window sum.
TEST(Features, TheWindowsBackgroundTakesAmbientLightOffERelAndF00) {
  Blob b;
  const cv::Mat clean = Render(b, 12);
  cv::Mat lit = clean.clone();
  for (int y = 0; y < lit.rows; ++y) {
    for (int x = 0; x < lit.cols; ++x) {
      const double ambient = 80.0 * (1.0 + 0.5 * (x - lit.cols / 2.0) / lit.cols);  // 2% of 12 bit
      lit.at<uint16_t>(y, x) = cv::saturate_cast<uint16_t>(lit.at<uint16_t>(y, x) + ambient);
    }
  }
  const Features c = ComputeFeatures(clean, 12, FeatureOptions());
  const Features a = ComputeFeatures(lit, 12, FeatureOptions());
  ASSERT_TRUE(c.blob_found && a.blob_found);
  EXPECT_NEAR(a.f00, c.f00, 2e-3 * c.f00);  // rounding of the added light only
  EXPECT_NEAR(a.e_rel, c.e_rel, 2e-3 * c.e_rel);
  EXPECT_NEAR(a.sigma, c.sigma, 2e-3 * c.sigma);
  const Features pc = ComputeFeatures(clean, 12, PaperFeatureOptions());
  const Features pa = ComputeFeatures(lit, 12, PaperFeatureOptions());
  EXPECT_GT(pa.f00 - pc.f00, 0.5 * 64 * 64 * 80.0 / 4095.0);  // the paper's features carry it
}

}  // namespace
}  // namespace irdist

namespace irdist {
namespace {

// The coarse pass's block means are cv::resize(INTER_AREA)'s values, rounding included: random
// 12- and 16-bit frames (every rounding tie occurs) at the downsampling factors the options allow
// that divide the frame, and a frame whose sides k does not divide (handed to cv::resize).
TEST(Features, DownsampleAreaIsOpenCvsAreaResize) {
  cv::RNG rng(7);
  for (const int max_level : {4095, 65535}) {
    for (int k = 2; k <= 8; ++k) {
      cv::Mat frame(k * 37, k * 45, CV_16UC1);
      rng.fill(frame, cv::RNG::UNIFORM, 0, max_level + 1);
      cv::Mat expected;
      cv::resize(frame, expected, cv::Size(45, 37), 0, 0, cv::INTER_AREA);
      const cv::Mat got = DownsampleArea(frame, k);
      ASSERT_EQ(got.size(), expected.size());
      EXPECT_EQ(cv::countNonZero(got != expected), 0) << "k " << k << ", max " << max_level;
    }
  }
  cv::Mat odd(130, 203, CV_16UC1);
  rng.fill(odd, cv::RNG::UNIFORM, 0, 4096);
  cv::Mat expected;
  cv::resize(odd, expected, cv::Size(203 / 4, 130 / 4), 0, 0, cv::INTER_AREA);
  EXPECT_EQ(cv::countNonZero(DownsampleArea(odd, 4) != expected), 0);
}

}  // namespace
}  // namespace irdist
