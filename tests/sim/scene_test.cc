#include "sim/scene.h"

#include <cmath>

#include <gtest/gtest.h>

#include "tests/sim/signal_moments.h"

namespace irdist::sim {
namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

PoseState Pose(double slide_mm, double pan_deg, double tilt_deg, double bias_ma = 500.0) {
  PoseState p;
  p.slide_mm = slide_mm;
  p.pan_deg = pan_deg;
  p.tilt_deg = tilt_deg;
  p.bias_ma = bias_ma;
  return p;
}

double Sum(const SignalWindow& w) { return cv::sum(w.electrons)[0]; }

// Eigenvalues of the intensity-weighted second-moment matrix of the window.
void Moments(const SignalWindow& w, double* major_var, double* minor_var) {
  const testing::Covariance m = testing::CovarianceOf(w);
  const double a = m.xx, b = m.yy, c = m.xy;
  const double mean = 0.5 * (a + b), diff = std::sqrt(0.25 * (a - b) * (a - b) + c * c);
  *major_var = mean + diff;
  *minor_var = mean - diff;
}

TEST(Scene, DiscImageIsResolvedAtThreeMetres) {
  const Scene scene{RigPhysics{}};
  const EmitterImage image = scene.Project(Pose(3000, 0, 0));
  EXPECT_GE(image.major_px, 8.0);
  EXPECT_NEAR(image.center_x_px, 640.0, 1e-9);
  EXPECT_NEAR(image.center_y_px, 512.0, 1e-9);
}

// The projected disc is an ellipse with axis ratio cos(theta). Measured from the noise-free
// signal's second moments, after removing the PSF's and the pixel box's variance
// (psf^2 + 1/12 px^2 per axis). Tolerance 0.01 on the ratio (the pixel grid and perspective).
TEST(Scene, EllipseAxisRatioIsCosTheta) {
  const Scene scene{RigPhysics{}};
  struct Case {
    double d, pan, tilt;
  };
  for (const Case& k : {Case{1500, 0, 0}, Case{1500, 30, 0}, Case{2000, 0, 20}, Case{2500, 20, 20},
                        Case{3000, 35, 0}, Case{3000, 10, 0}}) {
    const PoseState pose = Pose(k.d, k.pan, k.tilt);
    const double blur = scene.BlurSigmaPx(k.d);
    const double blur_var = blur * blur + 1.0 / 12.0;
    double major_var = 0, minor_var = 0;
    Moments(scene.RenderSignal(pose, 100.0, 0.01), &major_var, &minor_var);
    const double ratio = std::sqrt((minor_var - blur_var) / (major_var - blur_var));
    EXPECT_NEAR(ratio, std::cos(pose.ThetaDeg() * kDeg), 0.01)
        << "d " << k.d << " pan " << k.pan << " tilt " << k.tilt;
    // A uniform disc of diameter D has a second moment of D^2 / 16 along its major axis.
    const double major_px = scene.Project(pose).major_px;
    EXPECT_NEAR(std::sqrt(major_var - blur_var), major_px / 4.0, 0.02 * major_px / 4.0);
  }
}

// The image is the disc convolved with the PSF and integrated over pixels, evaluated without
// sampling the sharp disc: as the blob's size and sub-pixel phase change with d, its moments and
// total signal must not jitter. (Sampling the disc's edge on 8x8 sub-pixels and blurring after
// the pixel grid moved theta from the moments by -0.2..+1.0 deg within 200 mm of d, and the
// total signal by 0.1 %.)
TEST(Scene, ShapeAndSignalDoNotDependOnPixelPhase) {
  const Scene scene{RigPhysics{}};
  struct Case {
    double pan, tilt;
  };
  for (const Case& k : {Case{10, 0}, Case{20, 0}, Case{0, 30}, Case{15, 15}}) {
    double first_flux = 0.0;
    for (double d = 2600; d <= 2800; d += 10) {
      const PoseState pose = Pose(d, k.pan, k.tilt);
      const double blur = scene.BlurSigmaPx(d);
      const double blur_var = blur * blur + 1.0 / 12.0;
      const SignalWindow w = scene.RenderSignal(pose, 100.0, 0.01);
      double major_var = 0, minor_var = 0;
      Moments(w, &major_var, &minor_var);
      const double theta_deg =
          std::acos(std::sqrt((minor_var - blur_var) / (major_var - blur_var))) / kDeg;
      EXPECT_NEAR(theta_deg, pose.ThetaDeg(), 0.01) << "d " << d << " pan " << k.pan;
      const double major_px = scene.Project(pose).major_px;
      EXPECT_NEAR(major_var - blur_var, major_px * major_px / 16.0, 1e-3 * major_px * major_px / 16)
          << "d " << d << " pan " << k.pan;
      const double flux = Sum(w) * d * d;  // constant: the signal falls as 1/d^2
      if (first_flux == 0.0) first_flux = flux;
      EXPECT_NEAR(flux / first_flux, 1.0, 1e-4) << "d " << d << " pan " << k.pan;
    }
  }
}

// Thin-lens defocus: the circle of confusion equals the geometric one built from the image
// distances (1/f = 1/d + 1/v; sensor at v_s, the point images at v_d, the cone of aperture f/N
// cut by the sensor: c = (f/N) |v_d - v_s| / v_d), at three distances; the blob's rendered
// variance grows over the in-focus render by exactly c^2 / 16 (a uniform disc's per-axis variance).
TEST(Scene, DefocusFollowsThinLensCircleOfConfusion) {
  RigPhysics physics;
  physics.optics.focus_mm = 2000.0;
  const Scene scene{physics};
  RigPhysics fixed = physics;
  fixed.optics.focus_mm = 0.0;
  const Scene sharp{fixed};
  const double f = physics.optics.focal_length_mm, aperture = f / physics.optics.f_number;
  const double v_s = 1.0 / (1.0 / f - 1.0 / physics.optics.focus_mm);
  const double pitch_mm = physics.sensor.pixel_pitch_um * 1e-3;
  for (double d : {1500.0, 2000.0, 3000.0}) {
    const double v_d = 1.0 / (1.0 / f - 1.0 / d);
    const double coc_px = aperture * std::fabs(v_d - v_s) / v_d / pitch_mm;
    EXPECT_NEAR(scene.CircleOfConfusionPx(d), coc_px, 1e-9 * (1.0 + coc_px)) << d;
    double major = 0, minor = 0, major_sharp = 0, minor_sharp = 0;
    Moments(scene.RenderSignal(Pose(d, 0, 0), 100.0, 0.01), &major, &minor);
    Moments(sharp.RenderSignal(Pose(d, 0, 0), 100.0, 0.01), &major_sharp, &minor_sharp);
    EXPECT_NEAR(major - major_sharp, coc_px * coc_px / 16.0, 2e-3) << d;
    EXPECT_NEAR(minor - minor_sharp, coc_px * coc_px / 16.0, 2e-3) << d;
  }
  // The figure: a 16 mm f/8 lens focused at 2 m blurs 1.5 m and 3 m by ~one 5.3 um pixel.
  EXPECT_NEAR(scene.CircleOfConfusionPx(1500.0), 1.01, 0.01);
  EXPECT_NEAR(scene.CircleOfConfusionPx(3000.0), 1.01, 0.01);
  EXPECT_EQ(scene.CircleOfConfusionPx(2000.0), 0.0);
  EXPECT_EQ(sharp.CircleOfConfusionPx(1500.0), 0.0);
}

TEST(Scene, TotalSignalFallsAsInverseSquareOfDistance) {
  const Scene scene{RigPhysics{}};
  const double s1500 = Sum(scene.RenderSignal(Pose(1500, 0, 0), 100.0, 0.01));
  for (double d : {2000.0, 2500.0, 3000.0}) {
    const double s = Sum(scene.RenderSignal(Pose(d, 0, 0), 100.0, 0.01));
    EXPECT_NEAR(s / s1500, std::pow(1500.0 / d, 2), 0.002 * std::pow(1500.0 / d, 2)) << d;
  }
}

TEST(Scene, TotalSignalFollowsEmissionPatternTimesDirection) {
  // The total flux into the lens is I(theta) = I0 rho(theta), whatever the foreshortening.
  const Scene scene{RigPhysics{}};
  const double s0 = Sum(scene.RenderSignal(Pose(2000, 0, 0), 100.0, 0.01));
  const double s30 = Sum(scene.RenderSignal(Pose(2000, 30, 0), 100.0, 0.01));
  EXPECT_NEAR(s30 / s0, scene.Pattern(30 * kDeg), 0.005);
  EXPECT_NEAR(scene.Pattern(30 * kDeg), std::exp(-0.5), 1e-12);  // sigma 30 deg
}

TEST(Scene, CosPowerPatternSelectable) {
  RigPhysics p;
  p.emitter.pattern = EmissionPattern::kCosPower;
  p.emitter.pattern_cos_power = 3.0;
  const Scene scene(p);
  EXPECT_NEAR(scene.Pattern(40 * kDeg), std::pow(std::cos(40 * kDeg), 3.0), 1e-12);
}

TEST(Scene, IntensityIsLinearAboveThreshold) {
  const Scene scene{RigPhysics{}};
  const double th = RigPhysics{}.emitter.threshold_ma;
  EXPECT_EQ(scene.OnAxisIntensityMwSr(th - 1.0, 0.0), 0.0);
  const double i475 = scene.OnAxisIntensityMwSr(475, 0.0);
  const double i500 = scene.OnAxisIntensityMwSr(500, 0.0);
  EXPECT_NEAR(i500 / i475, (500 - th) / (475 - th), 1e-12);
  RigPhysics p;
  p.emitter.sublinear_per_ma = 2e-4;
  EXPECT_LT(Scene(p).OnAxisIntensityMwSr(500, 0.0), i500);
}

TEST(Scene, SelfHeatingFollowsFirstOrderModel) {
  const RigPhysics p;
  const Scene scene(p);
  const std::vector<CurrentStep> history = {{10.0, 500.0}};
  const double steady = p.emitter.thermal_resistance_k_per_w * 0.5 * p.emitter.forward_voltage_v;
  const double tau = p.emitter.thermal_time_constant_s;
  EXPECT_EQ(scene.JunctionRiseK(history, 5.0), 0.0);
  EXPECT_NEAR(scene.JunctionRiseK(history, 10.0 + tau), steady * (1 - std::exp(-1.0)), 1e-9);
  EXPECT_NEAR(scene.JunctionRiseK(history, 10.0 + 20 * tau), steady, 1e-6);
  // Switching off cools back down with the same time constant.
  const std::vector<CurrentStep> on_off = {{0.0, 500.0}, {20 * tau, 0.0}};
  EXPECT_NEAR(scene.JunctionRiseK(on_off, 21 * tau), steady * std::exp(-1.0), 1e-6);
  // The intensity drifts down by temp_coeff per kelvin.
  const double cold = scene.OnAxisIntensityMwSr(500, 0.0);
  EXPECT_NEAR(scene.OnAxisIntensityMwSr(500, steady) / cold,
              1.0 + p.emitter.temp_coeff_per_k * steady, 1e-12);
}

}  // namespace
}  // namespace irdist::sim
