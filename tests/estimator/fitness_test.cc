// The fit's fitness (estimator/fitness.h) on synthetic calibrations: a geometric model and frames
// whose sizes are its prediction times (1 + noise), and then the three faults it must tell apart.
#include "estimator/fitness.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "base/check.h"
#include "estimator/fit.h"
#include "estimator/fit_tilt.h"

namespace irdist {
namespace {

constexpr double kNoise = 0.003;  // per-frame relative scatter of a moment variance

CalibrationModel Geometric() {
  CalibrationModel model;
  model.geometric.alpha_px2 = 40.0;
  model.geometric.beta_px2 = 0.6;
  model.geometric.blur_u2_px2 = 0.1;
  return model;
}

struct Grid {
  std::vector<CalibrationSample> samples;
  std::vector<FitnessPose> poses;
};

// 4 distances x 8 angles x 2 currents, 4 measurement frames each; `distort(pose, frame, theta,
// &major, &minor)` changes the frame's relative sizes (1 = the model's).
template <typename Distort>
Grid MakeGrid(const CalibrationModel& model, Distort distort, unsigned seed = 7) {
  Grid g;
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, kNoise);
  for (double d_mm : {1500.0, 2000.0, 2500.0, 3000.0}) {
    for (int a = 0; a < 8; ++a) {
      for (double bias_ma : {475.0, 500.0}) {
        const double theta_deg = 5.0 * a;
        const int pose = static_cast<int>(g.poses.size());
        g.poses.push_back({d_mm, theta_deg, 0.0, bias_ma});
        const double cos_t = std::cos(theta_deg * M_PI / 180.0);
        const double major = model.geometric.MajorVarPx2(d_mm);
        const double minor = model.geometric.alpha_px2 * 1e6 / (d_mm * d_mm) * cos_t * cos_t +
                             model.geometric.BlurVarPx2(d_mm);
        for (int frame = 0; frame < 4; ++frame) {
          CalibrationSample s;
          s.d_mm = d_mm;
          s.theta_deg = theta_deg;
          s.bias_ma = bias_ma;
          s.pose = pose;
          for (Features* f : {&s.reference, &s.measurement}) f->blob_found = true;
          double major_rel = 1.0 + noise(rng), minor_rel = 1.0 + noise(rng);
          distort(pose, frame, theta_deg, &major_rel, &minor_rel);
          s.measurement.moment_major_var_px2 = major * major_rel;
          s.measurement.moment_minor_var_px2 = minor * minor_rel;
          g.samples.push_back(s);
        }
      }
    }
  }
  return g;
}

void Unchanged(int, int, double, double*, double*) {}

TEST(Fitness, AModelThatFitsItsFramesPasses) {
  const CalibrationModel model = Geometric();
  const Grid g = MakeGrid(model, Unchanged);
  const CalibrationFitness f = AssessFitness(model, g.samples, g.poses);
  ASSERT_TRUE(f.assessed);
  EXPECT_TRUE(f.passed) << f.BriefReport();
  EXPECT_EQ(f.poses, 64);
  EXPECT_EQ(f.dof, 64 * 2 - 4);  // two size channels per pose, four geometric parameters
  EXPECT_LT(f.reduced_chi2, f.limit);
  EXPECT_EQ(f.poses_over, 0);
  EXPECT_TRUE(f.cause.empty());
  EXPECT_EQ(f.worst.size(), 5u);
}

// Without the model-error floor, the figure is the noise's alone: a reduced chi-square near the
// noise's own 1 (the scatter is measured inside the brackets, not from the fit).
TEST(Fitness, WithoutFloorsTheFigureIsTheNoisesChiSquare) {
  const CalibrationModel model = Geometric();
  const Grid g = MakeGrid(model, Unchanged);
  FitnessOptions options;
  options.size_floor = 0.0;
  const CalibrationFitness f = AssessFitness(model, g.samples, g.poses, options);
  EXPECT_GT(f.reduced_chi2, 0.6);
  EXPECT_LT(f.reduced_chi2, 1.4);
}

// A tilt term in the model (fit.h GeometricModel::tilt_var_px2): the frames whose major axis
// departs from the law by it, as a blob fit's frames at their own theta, are judged as the
// estimate reads them (less the term) and pass; the same frames under the law alone do not.
TEST(Fitness, TheSizeIsJudgedLessTheModelsTiltTerm) {
  CalibrationModel model = Geometric();
  model.geometric.tilt_theta_deg = {0.0, 15.0, 35.0};
  model.geometric.tilt_var_px2 = {0.0, 0.0, -0.05};
  const GeometricModel& law = model.geometric;
  Grid g = MakeGrid(model, Unchanged);
  for (CalibrationSample& s : g.samples) {
    Features& f = s.measurement;
    f.size_blur_var_px2 = law.BlurVarPx2(s.d_mm);  // as the blob fit adds it
    const double major = f.moment_major_var_px2;
    for (int i = 0; i < 5; ++i) {  // the term at the theta of the frame that carries it
      f.moment_major_var_px2 = major + law.TiltVarPx2(FrameDiscThetaDeg(f));
    }
  }
  const CalibrationFitness with = AssessFitness(model, g.samples, g.poses);
  EXPECT_TRUE(with.passed) << with.BriefReport();
  CalibrationModel without = model;
  without.geometric.tilt_theta_deg.clear();
  without.geometric.tilt_var_px2.clear();
  EXPECT_FALSE(AssessFitness(without, g.samples, g.poses).passed);
}

// An elliptical PSF at theta 0: the minor axis 4% wider than the disc-plus-round-blur predicts
// where the disc is round, fading as the tilt's foreshortening takes over: most poses miss.
TEST(Fitness, AnOpticOutsideTheFamilyFailsAndSaysSo) {
  const CalibrationModel model = Geometric();
  const Grid g = MakeGrid(model, [](int, int, double theta_deg, double*, double* minor) {
    *minor *= 1.0 + 0.04 * std::cos(theta_deg * M_PI / 90.0);
  });
  const CalibrationFitness f = AssessFitness(model, g.samples, g.poses);
  EXPECT_FALSE(f.passed);
  EXPECT_GT(f.reduced_chi2, f.limit);
  EXPECT_GE(f.poses_over, 16) << f.BriefReport();
  EXPECT_NE(f.cause.find("outside the model's family"), std::string::npos) << f.cause;
  ASSERT_FALSE(f.worst.empty());
  EXPECT_EQ(f.worst.front().worst_channel, "minor");
  EXPECT_LE(f.worst.front().pose.pan_deg, 10.0);  // where the disc is round
}

// One pose where the IRED moved during the bracket: its frames disagree among themselves.
TEST(Fitness, APoseWhoseFramesDisagreeIsAMovingStage) {
  const CalibrationModel model = Geometric();
  const int moved = 21;
  const Grid g = MakeGrid(model, [moved](int pose, int frame, double, double* major, double* minor) {
    if (pose != moved) return;
    *major *= 1.0 + 0.03 * frame;
    *minor *= 1.0 + 0.03 * frame;
  });
  const CalibrationFitness f = AssessFitness(model, g.samples, g.poses);
  EXPECT_FALSE(f.passed);
  ASSERT_FALSE(f.worst.empty());
  EXPECT_EQ(f.worst.front().pose.slide_mm, g.poses[moved].slide_mm);
  EXPECT_EQ(f.worst.front().pose.pan_deg, g.poses[moved].pan_deg);
  EXPECT_NE(f.cause.find("moved during a bracket"), std::string::npos) << f.cause;
  EXPECT_NE(f.cause.find(PoseText(g.poses[moved])), std::string::npos) << f.cause;
}

// One pose whose frames agree but all miss (a reflection there, or the stage off its position).
TEST(Fitness, AFewPosesOffTogetherAreASceneFault) {
  const CalibrationModel model = Geometric();
  const Grid g = MakeGrid(model, [](int pose, int, double, double* major, double* minor) {
    if (pose != 40) return;
    *major *= 1.05;
    *minor *= 1.05;
  });
  const CalibrationFitness f = AssessFitness(model, g.samples, g.poses);
  EXPECT_FALSE(f.passed);
  EXPECT_EQ(f.poses_over, 1);
  EXPECT_EQ(f.worst.front().pose.slide_mm, g.poses[40].slide_mm);
  EXPECT_NEAR(f.worst.front().worst_residual_percent, 5.0, 0.5);
  EXPECT_NE(f.cause.find("scene fault"), std::string::npos) << f.cause;
}

TEST(Fitness, TooFewPosesAreNotAssessed) {
  const CalibrationModel model = Geometric();
  Grid g = MakeGrid(model, Unchanged);
  for (CalibrationSample& s : g.samples) s.pose = s.pose == 0 ? 0 : -1;
  const CalibrationFitness f = AssessFitness(model, g.samples, g.poses);
  EXPECT_FALSE(f.assessed);
  EXPECT_TRUE(f.passed);
}

TEST(Fitness, OptionsAreChecked) {
  FitnessOptions options;
  options.tail_probability = 0.0;
  std::string why;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_THROW(AssessFitness(Geometric(), {}, {}, options), Error);
}

}  // namespace
}  // namespace irdist
