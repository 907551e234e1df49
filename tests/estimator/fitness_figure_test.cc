// The fitness figure's text (estimator/fitness_figure.h): a pose as the causes and reports name
// it, the brief report, and the probable cause from the pattern of the worst poses. The figure's
// computation is estimator/fitness.
#include "estimator/fitness_figure.h"

#include <gtest/gtest.h>

#include <string>

namespace irdist {
namespace {

FitnessPose At(double slide_mm, double pan_deg) {
  return FitnessPose{slide_mm, pan_deg, 0.0, 500.0};
}

// A failed figure over 40 poses with a pose limit of 20 and one named worst pose.
CalibrationFitness Failed(int poses_over, double worst_scatter_ratio) {
  CalibrationFitness f;
  f.assessed = true;
  f.poses = 40;
  f.pose_limit = 20.0;
  f.poses_over = poses_over;
  f.passed = false;
  PoseFitness worst;
  worst.pose = At(3000.0, 35.0);
  worst.chi2 = 80.0;
  worst.scatter_ratio = worst_scatter_ratio;
  f.worst = {worst};
  return f;
}

TEST(FitnessFigure, PoseTextNamesTheAxesAndTheCurrent) {
  EXPECT_EQ(PoseText(At(2000.0, 10.0)), "slide 2000 mm, pan 10 deg, tilt 0 deg, 500 mA");
  EXPECT_EQ(PoseText(FitnessPose{1234.5, -7.25, 3.5, 475.0}),
            "slide 1234.5 mm, pan -7.25 deg, tilt 3.5 deg, 475 mA");
}

TEST(FitnessFigure, BriefReportSaysNotAssessedOrTheFigureAndItsWorstPoses) {
  EXPECT_EQ(CalibrationFitness().BriefReport(),
            "fitness: not assessed (fewer than 2 poses with frames to compare)");
  CalibrationFitness f = Failed(1, 1.2);
  f.reduced_chi2 = 1.5;
  f.dof = 180;
  f.limit = 1.27;
  f.tail_probability = 0.001;
  f.size_floor = 0.001;
  f.difference_floor = 0.001;
  f.worst[0].channels = 4;
  f.worst[0].worst_channel = "minor";
  f.worst[0].worst_residual_percent = 0.41;
  const std::string report = f.BriefReport();
  EXPECT_EQ(report.rfind("fitness: reduced chi-square 1.5 over 180 degrees of freedom (limit "
                         "1.27 at tail probability 0.001; model-error floors 0.1% size, 0.1% "
                         "dE/dSigma); 1 of 40 poses beyond 20: FAILED",
                         0),
            0u)
      << report;
  EXPECT_NE(report.find("\n    slide 3000 mm, pan 35 deg, tilt 0 deg, 500 mA: chi2 80 (4 "
                        "channels), worst minor +0.41%, scatter 1.2x its distance's"),
            std::string::npos)
      << report;
}

// A failing pose whose own frames scatter 10x beyond its distance's: the IRED or stage moved.
TEST(FitnessFigure, CauseIsMotionWhenAFailingPoseScattersWithinItself) {
  const std::string cause = FitnessCause(Failed(1, 12.0));
  EXPECT_EQ(cause.rfind("the IRED or the stage moved during a bracket", 0), 0u) << cause;
  EXPECT_NE(cause.find("slide 3000 mm, pan 35 deg"), std::string::npos) << cause;
  EXPECT_NE(cause.find("(12x the scatter"), std::string::npos) << cause;
}

// Many poses over (at least 3 and a quarter of them): an optic outside the models' family; a
// few: a scene fault at those poses.
TEST(FitnessFigure, CauseIsTheOpticWhenManyPosesMissAndTheSceneWhenFew) {
  const std::string optic = FitnessCause(Failed(10, 1.0));
  EXPECT_EQ(optic.rfind("an optic outside the model's family: 10 of 40 poses miss", 0), 0u)
      << optic;
  const std::string scene = FitnessCause(Failed(9, 1.0));
  EXPECT_EQ(scene.rfind("a scene fault at a few poses (9 of 40 miss", 0), 0u) << scene;
  // A scattering pose under the pose limit is no motion.
  CalibrationFitness calm = Failed(2, 50.0);
  calm.worst[0].chi2 = 5.0;
  EXPECT_EQ(FitnessCause(calm).rfind("a scene fault", 0), 0u);
}

}  // namespace
}  // namespace irdist
