// Accuracy regression on the virtual rig: frames rendered with sim::Renderer (sensor noise, the
// IRED's steady self-heating), a reduced Table 3 calibration, validation at off-grid poses and
// currents. Bounds are the issue-6 goals themselves (the reduced grid has fewer calibration
// poses and exposures than Table 3); bench/accuracy has the full study.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <memory>
#include <string>
#include <vector>

#include "estimator/blob_fit.h"
#include "estimator/estimate.h"
#include "estimator/estimate_baselines.h"
#include "estimator/features.h"
#include "estimator/fit.h"
#include "estimator/health.h"
#include "estimator/line_of_sight.h"
#include "sim/renderer.h"
#include "sim/rig_physics.h"

namespace irdist {
namespace {

constexpr double kTRefMs = 8.0;

struct Bracket {
  double d_mm, theta_deg, bias_ma;
  Features reference;
  std::vector<Features> measurements;
  std::vector<double> t_ms;
};

double SampleSd(const std::vector<double>& x) {
  double mean = 0.0, var = 0.0;
  for (double v : x) mean += v / x.size();
  for (double v : x) var += (v - mean) * (v - mean) / (x.size() - 1);
  return std::sqrt(var);
}

class AccuracyTest : public ::testing::Test {
 protected:
  AccuracyTest()
      : physics_(
            sim::LoadRigPhysics(std::string(IRDIST_SOURCE_DIR) + "/recipes/rigs/virtual.yaml")),
        renderer_(physics_) {}

  Bracket Render(double d_mm, double theta_deg, double bias_ma, const std::vector<double>& t_ms,
                 const FeatureOptions& fo) {
    Bracket b{d_mm, theta_deg, bias_ma, {}, {}, t_ms};
    const auto& e = physics_.emitter;
    const double rise_k = e.thermal_resistance_k_per_w * bias_ma * 1e-3 * e.forward_voltage_v;
    const int side = 160;
    const cv::Point origin(physics_.sensor.width_px / 2 - side / 2 + shift_px_.x,
                           physics_.sensor.height_px / 2 - side / 2 + shift_px_.y);
    cv::Mat frame(side, side, CV_16UC1);
    std::vector<double> all = {kTRefMs};
    all.insert(all.end(), t_ms.begin(), t_ms.end());
    for (size_t k = 0; k < all.size(); ++k) {
      sim::FrameConditions c = sim::StaticConditions(d_mm, theta_deg, 0.0, bias_ma, all[k] * 1e-3);
      c.junction_rise_k = rise_k;
      (changed_ ? *changed_ : renderer_)
          .Render(c, ++frame_index_, sim::PixelFormat::kMono12, origin, frame);
      Features f = ComputeFeatures(frame, 12, fo);
      if (refine_ != nullptr) {  // every frame, as the app does: the reference's size counts too
        if (raw_axes_) {
          RefineWithRawAxes(frame, *refine_, &f);
        } else {
          RefineWithBlobFit(frame, 12, *refine_, &f);
        }
      }
      if (k == 0) {
        b.reference = f;
      } else {
        b.measurements.push_back(f);
      }
    }
    return b;
  }

  // RefineWithBlobFit as it was before a round blob's anisotropy noise was removed: the fitted
  // P's eigenvalues as they are (the larger of two noisy axes is the major).
  static void RefineWithRawAxes(const cv::Mat& frame, const CalibrationModel& model, Features* f) {
    const GeometricModel& g = model.geometric;
    const double blur = g.BlurVarPx2(g.DistanceMm(f->moment_major_var_px2));
    const BlobFitResult fit = FitBlob(frame, 12, *f, blur);
    if (!fit.ok) return;
    f->moment_major_var_px2 = fit.raw_major_var_px2 + blur;
    f->moment_minor_var_px2 = fit.raw_minor_var_px2 + blur;
  }

  CalibrationModel Calibrate(const FeatureOptions& fo, const FitOptions& fit) {
    std::vector<CalibrationSample> samples;
    for (double d : {1500.0, 2000.0, 2500.0, 3000.0}) {
      for (double th : {0.0, 10.0, 20.0, 30.0, 35.0}) {
        for (double i : {475.0, 500.0}) {
          const Bracket b = Render(d, th, i, {30.0, 34.0}, fo);
          for (size_t k = 0; k < b.t_ms.size(); ++k) {
            CalibrationSample s;
            s.reference = b.reference;
            s.measurement = b.measurements[k];
            s.t_ref_ms = kTRefMs;
            s.t_ms = b.t_ms[k];
            s.bias_ma = i;
            s.d_mm = d;
            s.theta_deg = th;
            samples.push_back(s);
          }
        }
      }
    }
    return Fit(samples, fo, fit);
  }

  // Renders with the lens PSF changed so that the total blur at 2250 mm (the middle of the
  // calibrated range) changes by `change` (0: back to the calibrated rig).
  void ChangeBlur(double change) {
    if (change == 0.0) {
      changed_.reset();
      return;
    }
    const sim::Scene scene(physics_);
    const double total = scene.BlurSigmaPx(2250.0) * (1.0 + change);
    const double coc = scene.CircleOfConfusionPx(2250.0);
    sim::RigPhysics p = physics_;
    p.optics.psf_sigma_px = std::sqrt(total * total - coc * coc / 16.0);
    changed_ = std::make_unique<sim::Renderer>(p);
  }

  sim::RigPhysics physics_;
  sim::Renderer renderer_;
  std::unique_ptr<sim::Renderer> changed_;
  const CalibrationModel* refine_ = nullptr;  // frames through RefineWithBlobFit
  bool raw_axes_ = false;  // ... or through RefineWithRawAxes
  cv::Point shift_px_{0, 0};  // the rendered window's offset from the sensor's centre
  std::uint64_t frame_index_ = 0;
};

// The shipped rig is defocused (a 16 mm f/8 lens focused at 2 m): the blur grows in front of and
// behind 2 m. Calibrated on this grid, the default pipeline keeps the issue-12 distance goal at
// off-grid poses (max relative error <= 0.3%), with no margin.
TEST_F(AccuracyTest, DefocusedRigMeetsTheDistanceGoal) {
  ASSERT_GT(physics_.optics.focus_mm, 0.0);
  const FeatureOptions fo;
  const CalibrationModel model = Calibrate(fo, FitOptions());
  ASSERT_TRUE(model.geometric.BlurVariesWithDistance());
  const EstimateOptions eo;
  double worst = 0.0, worst_theta = 0.0;
  for (double d : {1600.0, 2100.0, 2700.0, 2900.0}) {
    for (double th : {0.0, 15.0, 25.0}) {
      const Bracket b = Render(d, th, 500.0, {32.0, 35.0}, fo);
      const BracketEstimate e =
          EstimateBracket(model, b.reference, kTRefMs, b.measurements, b.t_ms, eo);
      const double rel = std::abs(e.joint.d_mm / d - 1.0);
      EXPECT_LE(rel, 0.003) << "d " << d << " theta " << th << ": " << e.joint.BriefReport();
      worst = std::max(worst, rel);
      if (th >= 15.0) worst_theta = std::max(worst_theta, std::abs(e.joint.theta_deg - th));
    }
  }
  std::printf("defocused rig: worst relative error %.3f%%, theta (>= 15 deg) %.2f deg\n",
              100 * worst, worst_theta);
}

// The blob fit with the calibrated blur (estimator/blob_fit.h) on the Fig. 14 pose (2.7 m, 500 mA,
// pair 8/35 ms, 100 repetitions) at 20 and 30 deg: the distance's and theta's dispersion within
// 1.3x the Cramer-Rao bound of the same pair (d 1.81 / 2.10 mm, theta 0.163 / 0.122 deg,
// `irdist_accuracy_study --crb-only`), and the distance's below the second moments' on the same
// noise. (The theta goal "max <= 0.5 deg" over 100 repetitions is not asserted: at 20 deg an
// estimator AT the bound exceeds it in ~19% of runs, docs/estimator.md.)
TEST_F(AccuracyTest, BlobFitMeetsTheDispersionGoalAtFig14) {
  const FeatureOptions fo;
  const CalibrationModel model = Calibrate(fo, FitOptions());
  const EstimateOptions eo;
  struct Bound {
    double theta_deg, d_mm, theta_sd_deg;
  };
  for (const Bound& bound : {Bound{20.0, 1.81, 0.163}, Bound{30.0, 2.10, 0.122}}) {
    const double th = bound.theta_deg;
    double sd_mm[2] = {0.0, 0.0}, sd_theta[2] = {0.0, 0.0}, worst_theta[2] = {0.0, 0.0};
    for (int method = 0; method < 2; ++method) {  // 0: second moments, 1: blob fit
      refine_ = method == 1 ? &model : nullptr;
      frame_index_ = 100000;  // the same noise for both methods
      std::vector<double> d, t;
      for (int k = 0; k < 100; ++k) {
        const Bracket b = Render(2700.0, th, 500.0, {35.0}, fo);
        const BracketEstimate e =
            EstimateBracket(model, b.reference, kTRefMs, b.measurements, b.t_ms, eo);
        ASSERT_TRUE(std::isfinite(e.joint.d_mm));
        d.push_back(e.joint.d_mm);
        t.push_back(e.joint.theta_deg);
        worst_theta[method] = std::max(worst_theta[method], std::abs(e.joint.theta_deg - th));
      }
      sd_mm[method] = SampleSd(d);
      sd_theta[method] = SampleSd(t);
    }
    refine_ = nullptr;
    std::printf("2700 mm theta %g: sd d moments %.2f / blob fit %.2f mm (CRB %.2f); sd theta "
                "%.3f / %.3f deg (CRB %.3f); theta max %.2f / %.2f deg\n", th, sd_mm[0], sd_mm[1],
                bound.d_mm, sd_theta[0], sd_theta[1], bound.theta_sd_deg, worst_theta[0],
                worst_theta[1]);
    EXPECT_LE(sd_mm[1], 1.3 * bound.d_mm) << th;
    EXPECT_LT(sd_mm[1], sd_mm[0]) << th;
    EXPECT_LE(sd_theta[1], 1.3 * bound.theta_sd_deg) << th;
  }
}

// At theta 0 (Fig. 14's first pose: 2.7 m, 500 mA, pair 8/35 ms, 100 repetitions on the same
// noise) the blob's size without its anisotropy's noise bias gives a distance that scatters less
// than the larger of the fitted disc's two noisy axes did (measured 1.29 against 1.45 mm, the
// bound 1.01), is not biased short by it, and theta stays near 0 instead of the larger axis's
// +2.8 deg mean (docs/estimator.md).
TEST_F(AccuracyTest, ARoundBlobsDistanceScattersLessThanWithItsLargerAxis) {
  const FeatureOptions fo;
  const CalibrationModel model = Calibrate(fo, FitOptions());
  const EstimateOptions eo;
  double sd_mm[2], mean_mm[2], mean_theta[2];
  for (int method = 0; method < 2; ++method) {  // 0: the larger axis, 1: the default
    refine_ = &model;
    raw_axes_ = method == 0;
    frame_index_ = 200000;
    std::vector<double> d;
    mean_theta[method] = 0.0;
    for (int k = 0; k < 100; ++k) {
      const Bracket b = Render(2700.0, 0.0, 500.0, {35.0}, fo);
      const BracketEstimate e =
          EstimateBracket(model, b.reference, kTRefMs, b.measurements, b.t_ms, eo);
      ASSERT_TRUE(std::isfinite(e.joint.d_mm));
      d.push_back(e.joint.d_mm);
      mean_theta[method] += e.joint.theta_deg / 100.0;
    }
    sd_mm[method] = SampleSd(d);
    mean_mm[method] = std::accumulate(d.begin(), d.end(), 0.0) / d.size();
  }
  refine_ = nullptr;
  raw_axes_ = false;
  std::printf("2700 mm theta 0: sd d larger axis %.2f / default %.2f mm (CRB 1.01); mean error "
              "%+.2f / %+.2f mm; mean theta %.2f / %.2f deg\n", sd_mm[0], sd_mm[1],
              mean_mm[0] - 2700.0, mean_mm[1] - 2700.0, mean_theta[0], mean_theta[1]);
  EXPECT_LT(sd_mm[1], 0.92 * sd_mm[0]);
  // Within 1.3x the pair's bound at theta 0 too, now that the reference frame's size enters the
  // distance (1.12 mm here; 1.29 mm with the measurement frame's size alone).
  EXPECT_LE(sd_mm[1], 1.3 * 1.01);
  // The larger axis's upward size bias put d short; without it d moves toward the truth (what is
  // left, ~1 mm = 0.04%, is this reduced calibration's own bias at 2.7 m).
  EXPECT_GT(mean_mm[1] - mean_mm[0], 0.5);
  EXPECT_LT(std::abs(mean_mm[1] - 2700.0), std::abs(mean_mm[0] - 2700.0));
  EXPECT_LT(mean_theta[1], 0.5 * mean_theta[0]);
}

// Calibration health: the blur measured on each frame against the calibrated blur at the
// estimated distance. Unchanged rig: no estimate flagged; the blur 15% and 30% larger after
// calibration (a touched focus ring, a warm lens): every estimate flagged, with advice.
TEST_F(AccuracyTest, HealthFlagsABlurChangedAfterCalibration) {
  const FeatureOptions fo;
  const CalibrationModel model = Calibrate(fo, FitOptions());
  ASSERT_TRUE(model.blur_calibration.fitted());
  const EstimateOptions eo;
  for (double change : {0.0, 0.15, 0.30}) {
    ChangeBlur(change);
    int assessed = 0, flagged = 0;
    for (double d : {1600.0, 2100.0, 2700.0, 2900.0}) {
      for (double th : {0.0, 15.0, 30.0}) {
        const Bracket b = Render(d, th, 500.0, {35.0}, fo);
        const BracketEstimate e =
            EstimateBracket(model, b.reference, kTRefMs, b.measurements, b.t_ms, eo);
        const HealthCheck h = CheckHealth(model, e.joint.d_mm, {&b.measurements[0]});
        assessed += h.assessed ? 1 : 0;
        flagged += h.flagged ? 1 : 0;
        if (h.flagged) {
          EXPECT_EQ(std::string(h.Label()), change > 0 ? "blur_larger" : "blur_smaller");
          EXPECT_NE(h.Advice().find("recalibrate"), std::string::npos);
        }
      }
    }
    std::printf("blur %+.0f%%: %d of %d estimates flagged\n", 100 * change, flagged, assessed);
    EXPECT_EQ(assessed, 12) << change;
    EXPECT_EQ(flagged, change == 0.0 ? 0 : 12) << change;
  }
  ChangeBlur(0.0);
}

TEST_F(AccuracyTest, DefaultPipelineMeetsTheGoalsAtOffGridPoses) {
  const FeatureOptions fo;
  const CalibrationModel model = Calibrate(fo, FitOptions());
  const EstimateOptions eo;
  // The accuracy goals, with no margin: measured 0.12%, 0.23 deg, 0.11% on this grid.
  const double kMaxRelError = 0.010;
  const double kMaxThetaErrorDeg = 1.0;
  const double kMaxCurrentShift = 0.003;
  double worst = 0.0, worst_theta = 0.0, worst_shift = 0.0, worst_i0 = 0.0;
  for (double d : {1700.0, 2300.0, 2700.0}) {
    for (double th : {5.0, 15.0, 25.0}) {
      std::map<double, double> by_current;
      for (double i : {475.0, 525.0}) {
        const Bracket b = Render(d, th, i, {32.0, 35.0}, fo);
        ASSERT_TRUE(b.reference.Usable()) << b.reference.BriefReport();
        const BracketEstimate e =
            EstimateBracket(model, b.reference, kTRefMs, b.measurements, b.t_ms, eo);
        const double rel = std::abs(e.joint.d_mm / d - 1.0);
        EXPECT_LE(rel, kMaxRelError)
            << "d " << d << " theta " << th << " I " << i << ": " << e.joint.BriefReport();
        EXPECT_GT(e.joint.d_std_mm, 0.0);
        worst = std::max(worst, rel);
        if (th >= 15.0) {
          worst_theta = std::max(worst_theta, std::abs(e.joint.theta_deg - th));
          EXPECT_LE(std::abs(e.joint.theta_deg - th), kMaxThetaErrorDeg) << e.joint.BriefReport();
        }
        by_current[i] = e.joint.d_mm;
        const I0DependentEstimate di =
            EstimateI0Dependent(model, b.reference, kTRefMs, b.measurements, b.t_ms, 500.0);
        ASSERT_TRUE(di.valid);
        if (i == 525.0) worst_i0 = std::max(worst_i0, std::abs(di.d_mm / d - 1.0));
      }
      const double shift = std::abs(by_current[475.0] - by_current[525.0]) / d;
      EXPECT_LE(shift, kMaxCurrentShift) << "d " << d << " theta " << th;
      worst_shift = std::max(worst_shift, shift);
    }
  }
  // The I0-dependent estimate at the nominal 500 mA must see the 5% brighter IRED at 525 mA
  // (about 2.5% in d): the rendering and the drift reach the features.
  EXPECT_GT(worst_i0, 0.015);
  std::printf(
      "worst relative error %.3f%%, theta (>= 15 deg) %.2f deg, current shift %.3f%%, "
      "i0-dependent at 525 mA %.2f%%\n",
      100 * worst, worst_theta, 100 * worst_shift, 100 * worst_i0);
}

// Off the optical axis (the IRED 250 mm to the side: field angles 5.7-8.4 deg) a pinhole stretches
// the blob (1/cos^2 radially, 1/cos across) and its aperture takes cos of the flux: read as they
// are, the features give neither the range nor the tilt. The camera turned onto the line of sight
// (estimator/line_of_sight.h, the intrinsics of the rig's physics) reads the on-axis calibration's
// geometry: the range from the camera's centre and theta from the line of sight, as the sim's
// ray-traced pinhole drew them.
TEST_F(AccuracyTest, OffTheAxisTheTurnedCameraReadsTheRangeAndTheTilt) {
  const FeatureOptions fo;
  const CalibrationModel model = Calibrate(fo, FitOptions());
  refine_ = &model;
  constexpr double kSideMm = 250.0;
  sim::RigPhysics off = physics_;
  off.emitter.offset_x_mm = kSideMm;
  changed_ = std::make_unique<sim::Renderer>(off);
  const double f_px = physics_.optics.focal_length_mm / (physics_.sensor.pixel_pitch_um * 1e-3);
  double worst_turned = 0.0, worst_raw = 0.0, worst_theta = 0.0, worst_raw_theta = 0.0;
  for (double d : {1700.0, 2500.0}) {
    shift_px_ = cv::Point(static_cast<int>(std::lround(f_px * kSideMm / d)), 0);
    const cv::Point2d origin(physics_.sensor.width_px / 2 - 80 + shift_px_.x,
                             physics_.sensor.height_px / 2 - 80 + shift_px_.y);
    const RayOfPixel ray_of = [&](const cv::Point2d& p) {
      const cv::Point2d q = p + origin - cv::Point2d(0.5 * physics_.sensor.width_px - 0.5,
                                                     0.5 * physics_.sensor.height_px - 0.5);
      return cv::normalize(cv::Vec3d(q.x / f_px, q.y / f_px, 1.0));
    };
    for (double pan : {-20.0, 0.0, 20.0}) {
      const double range = std::hypot(d, kSideMm);
      const double p = pan * 3.14159265358979323846 / 180.0;
      const double theta = std::acos((d * std::cos(p) - kSideMm * std::sin(p)) / range) * 180.0 /
                           3.14159265358979323846;
      auto turn = [&](const Features& f) {
        return ToLineOfSight(f, LineOfSightAt(ray_of, f.centroid_px, f_px, f_px));
      };
      double d_error = 0.0, theta_error = 0.0, raw_d_error = 0.0, raw_theta_error = 0.0;
      constexpr int kBrackets = 3;  // a bracket's own noise: 0.05% and 0.1-0.2 deg here
      for (int k = 0; k < kBrackets; ++k) {
        Bracket b = Render(d, pan, 500.0, {32.0, 35.0}, fo);
        ASSERT_TRUE(b.reference.Usable()) << b.reference.BriefReport();
        const BracketEstimate raw = EstimateBracket(model, b.reference, kTRefMs, b.measurements,
                                                    b.t_ms, EstimateOptions());
        b.reference = turn(b.reference);
        for (Features& m : b.measurements) m = turn(m);
        const BracketEstimate e = EstimateBracket(model, b.reference, kTRefMs, b.measurements,
                                                  b.t_ms, EstimateOptions());
        d_error += (e.joint.d_mm / range - 1.0) / kBrackets;
        theta_error += (e.joint.theta_deg - theta) / kBrackets;
        raw_d_error += (raw.joint.d_mm / range - 1.0) / kBrackets;
        raw_theta_error += (raw.joint.theta_deg - theta) / kBrackets;
      }
      SCOPED_TRACE(testing::Message() << "d " << d << " pan " << pan << " theta " << theta);
      EXPECT_NEAR(d_error, 0.0, 6e-4);
      EXPECT_NEAR(theta_error, 0.0, 0.2);
      worst_turned = std::max(worst_turned, std::fabs(d_error));
      worst_raw = std::max(worst_raw, std::fabs(raw_d_error));
      worst_theta = std::max(worst_theta, std::fabs(theta_error));
      worst_raw_theta = std::max(worst_raw_theta, std::fabs(raw_theta_error));
    }
  }
  // The frame's own features miss by far more (the test's own control).
  EXPECT_GT(worst_raw, 3e-3);
  EXPECT_GT(worst_raw_theta, 2.0);
  std::printf("250 mm off the axis: turned worst %.3f%% %.2f deg, as framed %.3f%% %.2f deg\n",
              100 * worst_turned, worst_theta, 100 * worst_raw, worst_raw_theta);
}

// The standard error each estimate reports must describe its scatter, at every distance: 30
// repetitions of one pose (one 8/35 ms pair each) at 1.7 and 2.7 m, mean reported d_std against
// the measured sd of d. The apparent size's noise grows faster than d (the Cramer-Rao bound goes
// as d^2.6), which the geometric fit's noise model carries; in units of the mean calibration
// error alone the standard error grew only as d (1.6x from 1.7 to 2.7 m, against ~3x).
TEST_F(AccuracyTest, StandardErrorFollowsTheScatterAcrossDistance) {
  const FeatureOptions fo;
  const CalibrationModel model = Calibrate(fo, FitOptions());
  ASSERT_GT(model.geometric.noise_rel_at_1m, 0.0);
  ASSERT_GT(model.geometric.noise_exponent, 0.5);  // the apparent size's noise grows with d
  const EstimateOptions eo;
  double sd[2], se[2];
  const double distances[2] = {1700.0, 2700.0};
  constexpr int kReps = 80;
  for (int k = 0; k < 2; ++k) {
    std::vector<double> d_mm;
    double mean_std = 0.0;
    for (int rep = 0; rep < kReps; ++rep) {
      const Bracket b = Render(distances[k], 20.0, 500.0, {35.0}, fo);
      const BracketEstimate e =
          EstimateBracket(model, b.reference, kTRefMs, b.measurements, b.t_ms, eo);
      d_mm.push_back(e.joint.d_mm);
      mean_std += e.joint.d_std_mm / kReps;
    }
    double mean = 0.0, var = 0.0;
    for (double d : d_mm) mean += d / d_mm.size();
    for (double d : d_mm) var += (d - mean) * (d - mean) / (d_mm.size() - 1);
    sd[k] = std::sqrt(var);
    se[k] = mean_std;
    std::printf("%.0f mm, 20 deg: sd of d %.2f mm, mean reported standard error %.2f mm (%.2fx)\n",
                distances[k], sd[k], se[k], se[k] / sd[k]);
    // 80 repetitions estimate an sd to ~8%; the rest is the calibration's own noise model.
    EXPECT_GT(se[k] / sd[k], 0.7) << distances[k];
    EXPECT_LT(se[k] / sd[k], 1.6) << distances[k];
  }
  const double growth_sd = sd[1] / sd[0], growth_se = se[1] / se[0];
  std::printf("from 1.7 to 2.7 m: sd x%.2f, standard error x%.2f\n", growth_sd, growth_se);
  EXPECT_NEAR(growth_se / growth_sd, 1.0, 0.35);
}

TEST_F(AccuracyTest, PaperPipelineRunsAndStaysNearItsPublishedError) {
  const FeatureOptions fo = PaperFeatureOptions();
  const CalibrationModel model = Calibrate(fo, PaperFitOptions());
  std::vector<double> errors;
  for (double d : {1700.0, 2700.0}) {
    for (double th : {15.0, 25.0}) {
      const Bracket b = Render(d, th, 500.0, {32.0, 35.0}, fo);
      const BracketEstimate e = EstimateBracket(model, b.reference, kTRefMs, b.measurements, b.t_ms,
                                                PaperEstimateOptions());
      for (const DistanceEstimate& x : e.per_exposure) {
        ASSERT_TRUE(std::isfinite(x.d_mm));
        errors.push_back(std::abs(x.d_mm / d - 1.0));
      }
    }
  }
  // The paper: > 50% of its estimates within 2%. Its root vote can pick the wrong one of the two
  // in-range roots of the Sigma equation (tens of percent off), so only the median is bounded.
  std::sort(errors.begin(), errors.end());
  for (double e : errors) std::printf("%.2f%% ", 100 * e);
  std::printf("\n");
  EXPECT_LE(errors[errors.size() / 2], 0.02);
}


}  // namespace
}  // namespace irdist
