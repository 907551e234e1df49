// The fit judges itself, end to end on the virtual rig: a calibration whose frames the model's family
// cannot describe (a cable over 5% of the IRED's disc, moving with it: every pose's blob is a cut
// disc) fails its own fitness. calibrate warns with the worst poses and the probable cause, writes
// the model beside as model.rejected.yaml (never model.yaml) and exits non-zero; `irdist fit
// --keep-model` on the same recording writes model.yaml with the failing figure and exits 0.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>

#include "estimator/model_file.h"
#include "tests/integration/measure_helpers.h"
#include "tests/integration/run_helpers.h"
#include "tests/loopback_gvcp.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;
using testing::RunIrdist;
using testing::WriteAll;

// The shipped virtual rig with a cable over 5% of the disc (docs/virtual-rig.md, "A lab's scene").
std::string CableRig() {
  YAML::Node rig = YAML::LoadFile(std::string(IRDIST_SOURCE_DIR) + "/recipes/rigs/virtual.yaml");
  rig["virtual"]["scene"]["occluder"]["covered_fraction"] = 0.05;
  rig["virtual"]["scene"]["occluder"]["edge_angle_deg"] = 90;
  YAML::Emitter out;
  out << rig;
  return std::string(out.c_str()) + "\n";
}

class Fitness : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new std::string(testing::ScratchDir("fitness"));
    WriteAll(*dir_ + "/cable-rig.yaml", CableRig());
    std::string recipe = testing::SmallCalibrationRecipe("fitness-cable");
    recipe.replace(recipe.find("rig: virtual"), 12, "rig: " + *dir_ + "/cable-rig.yaml");
    WriteAll(*dir_ + "/calibration.yaml", recipe);
    testing::LoopbackGvcpLock lock;
    calibrate_code_ = RunIrdist({"calibrate", *dir_ + "/calibration.yaml", "--out", *dir_ + "/cal",
                                 "--time-scale", "50", "--quiet"},
                                *dir_ + "/calibrate.log", &calibrate_output_);
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  static std::string* dir_;
  static int calibrate_code_;
  static std::string calibrate_output_;
};

std::string* Fitness::dir_ = nullptr;
int Fitness::calibrate_code_ = -1;
std::string Fitness::calibrate_output_;

TEST_F(Fitness, ACalibrationOutsideTheFamilyWarnsNamesThePosesAndFails) {
  EXPECT_EQ(calibrate_code_, 1) << calibrate_output_;
  EXPECT_NE(calibrate_output_.find("misses its own calibration frames beyond their noise"),
            std::string::npos)
      << calibrate_output_;
  EXPECT_NE(calibrate_output_.find("Probable cause: an optic outside the model's family"),
            std::string::npos)
      << calibrate_output_;
  EXPECT_NE(calibrate_output_.find("worst: slide "), std::string::npos) << calibrate_output_;
  EXPECT_NE(calibrate_output_.find("--keep-model"), std::string::npos) << calibrate_output_;
  // The model is kept beside, never as model.yaml, which validate would take.
  EXPECT_FALSE(fs::exists(*dir_ + "/cal/model.yaml"));
  ASSERT_TRUE(fs::exists(*dir_ + "/cal/model.rejected.yaml")) << calibrate_output_;
  const CalibrationModel rejected = LoadModel(*dir_ + "/cal/model.rejected.yaml");
  ASSERT_TRUE(rejected.fitness.assessed);
  EXPECT_FALSE(rejected.fitness.passed);
  EXPECT_GT(rejected.fitness.reduced_chi2, rejected.fitness.limit);
  EXPECT_GE(rejected.fitness.poses_over, 6);  // a quarter of the 24 poses at least
  ASSERT_FALSE(rejected.fitness.worst.empty());
  EXPECT_GT(rejected.fitness.worst.front().chi2, rejected.fitness.pose_limit);
  EXPECT_NE(rejected.fitness.cause.find("outside the model's family"), std::string::npos);
}

TEST_F(Fitness, FitKeepsTheModelWhenToldTo) {
  ASSERT_TRUE(fs::exists(*dir_ + "/cal/recording")) << calibrate_output_;
  const std::string kept = *dir_ + "/kept/model.yaml";
  std::string output;
  EXPECT_EQ(RunIrdist({"fit", *dir_ + "/cal/recording", "--out", kept}, *dir_ + "/fit.log",
                      &output),
            1)
      << output;
  EXPECT_FALSE(fs::exists(kept));
  EXPECT_TRUE(fs::exists(*dir_ + "/kept/model.rejected.yaml"));
  EXPECT_EQ(RunIrdist({"fit", *dir_ + "/cal/recording", "--out", kept, "--keep-model", "--force"},
                      *dir_ + "/fit-kept.log", &output),
            0)
      << output;
  EXPECT_NE(output.find("warning: the model misses its own calibration frames"), std::string::npos)
      << output;
  EXPECT_NE(output.find("Kept as asked (--keep-model)"), std::string::npos) << output;
  // The kept model supersedes the rejected one the first fit left beside it: removed, and said.
  EXPECT_FALSE(fs::exists(*dir_ + "/kept/model.rejected.yaml"));
  EXPECT_NE(output.find("removed " + *dir_ + "/kept/model.rejected.yaml"), std::string::npos)
      << output;
  const CalibrationModel model = LoadModel(kept);
  ASSERT_TRUE(model.fitness.assessed);
  EXPECT_FALSE(model.fitness.passed);
}

}  // namespace
}  // namespace irdist
