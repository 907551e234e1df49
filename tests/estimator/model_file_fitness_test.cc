#include "estimator/model_file_fitness.h"

#include <gtest/gtest.h>

#include <string>

#include "estimator/model_file_error.h"

namespace irdist::model_file {
namespace {

std::string Emitted(const CalibrationFitness& fitness) {
  YAML::Emitter out;
  out << YAML::BeginMap << YAML::Key << "format" << YAML::Value << 5;
  EmitFitness(out, fitness);
  out << YAML::EndMap;
  return out.c_str();
}

CalibrationFitness Read(const std::string& yaml) {
  return ReadFitness(Reader("model.yaml"), YAML::Load(yaml));
}

// The header's example of the block, by hand.
const char kExample[] =
    "fitness:\n"
    "  passed: false\n"
    "  reduced_chi2: 0.93\n"
    "  dof: 180\n"
    "  limit: 1.27\n"
    "  pose_limit: 22.5\n"
    "  tail_probability: 0.001\n"
    "  size_floor: 0.004\n"
    "  difference_floor: 0.005\n"
    "  poses: 64\n"
    "  poses_over: 2\n"
    "  cause: \"the IRED moved\"\n"
    "  worst_poses:\n"
    "    - {slide_mm: 3000, pan_deg: 35, tilt_deg: -2, bias_ma: 475, chi2: 9.1, channels: 4,\n"
    "       scatter_ratio: 1.3, channel: minor, residual_percent: 0.41}\n"
    "    - {slide_mm: 1500, pan_deg: 0, tilt_deg: 0, bias_ma: 500, chi2: 7.5, channels: 3,\n"
    "       scatter_ratio: 0.8, channel: dE, residual_percent: -0.2}\n";

// Replaces the first `from` in kExample by `to`.
std::string ExampleWith(const std::string& from, const std::string& to) {
  std::string text = kExample;
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return text.replace(at, from.size(), to);
}

void ExpectRefused(const std::string& yaml, const std::string& key, const std::string& problem) {
  try {
    Read(yaml);
    ADD_FAILURE() << "accepted, expected a refusal at " << key;
  } catch (const ModelFileError& e) {
    EXPECT_EQ(e.key(), key);
    EXPECT_NE(std::string(e.what()).find(problem), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("model.yaml"), std::string::npos) << e.what();
  }
}

TEST(ModelFileFitness, ReadsTheDocumentedBlock) {
  const CalibrationFitness f = Read(kExample);
  ASSERT_TRUE(f.assessed);
  EXPECT_FALSE(f.passed);
  EXPECT_EQ(f.reduced_chi2, 0.93);
  EXPECT_EQ(f.dof, 180);
  EXPECT_NEAR(f.chi2, 0.93 * 180.0, 1e-12);  // not stored: the reduced figure times its dof
  EXPECT_EQ(f.limit, 1.27);
  EXPECT_EQ(f.pose_limit, 22.5);
  EXPECT_EQ(f.tail_probability, 0.001);
  EXPECT_EQ(f.size_floor, 0.004);
  EXPECT_EQ(f.difference_floor, 0.005);
  EXPECT_EQ(f.poses, 64);
  EXPECT_EQ(f.poses_over, 2);
  EXPECT_EQ(f.cause, "the IRED moved");
  ASSERT_EQ(f.worst.size(), 2u);
  EXPECT_EQ(f.worst[0].pose.slide_mm, 3000.0);
  EXPECT_EQ(f.worst[0].pose.pan_deg, 35.0);
  EXPECT_EQ(f.worst[0].pose.tilt_deg, -2.0);
  EXPECT_EQ(f.worst[0].pose.bias_ma, 475.0);
  EXPECT_EQ(f.worst[0].chi2, 9.1);
  EXPECT_EQ(f.worst[0].channels, 4);
  EXPECT_EQ(f.worst[0].scatter_ratio, 1.3);
  EXPECT_EQ(f.worst[0].worst_channel, "minor");
  EXPECT_EQ(f.worst[0].worst_residual_percent, 0.41);
  EXPECT_EQ(f.worst[1].worst_channel, "dE");
  EXPECT_EQ(f.worst[1].worst_residual_percent, -0.2);
}

// A model not assessed (or from before the figure) has no block, and reading none, or an empty
// one, gives a figure not assessed.
TEST(ModelFileFitness, AbsentMeansNotAssessed) {
  CalibrationFitness unassessed;
  unassessed.reduced_chi2 = 3.0;  // ignored: not assessed
  const std::string text = Emitted(unassessed);
  EXPECT_EQ(text.find("fitness"), std::string::npos) << text;
  EXPECT_FALSE(Read(text).assessed);
  EXPECT_FALSE(Read("format: 5\nfitness: ~\n").assessed);
}

// Written and read back, every number is the same double and the cause's text is kept whole
// (quotes and a colon in it included).
TEST(ModelFileFitness, RoundTripsEveryFieldExactly) {
  CalibrationFitness f;
  f.assessed = true;
  f.passed = true;
  f.poses = 48;
  f.dof = 133;
  f.reduced_chi2 = 2.0 / 3.0;
  f.limit = 1.0 + 1.0 / 7.0;
  f.pose_limit = 25.0 / 3.0;
  f.tail_probability = 1e-3;
  f.size_floor = 0.004;
  f.difference_floor = 1.0 / 300.0;
  f.poses_over = 0;
  f.cause = "a \"second\" source: see pose 3";
  f.worst.push_back({{2999.5, -35.25, 0.125, 487.5}, 90.0 / 7.0, 4, 1.0 / 3.0, "dSigma", -2.0 / 3.0});
  const std::string text = Emitted(f);
  const CalibrationFitness back = Read(text);
  ASSERT_TRUE(back.assessed);
  EXPECT_TRUE(back.passed);
  EXPECT_EQ(back.reduced_chi2, f.reduced_chi2);
  EXPECT_EQ(back.limit, f.limit);
  EXPECT_EQ(back.pose_limit, f.pose_limit);
  EXPECT_EQ(back.difference_floor, f.difference_floor);
  EXPECT_EQ(back.chi2, f.reduced_chi2 * f.dof);
  EXPECT_EQ(back.cause, f.cause);
  ASSERT_EQ(back.worst.size(), 1u);
  EXPECT_EQ(back.worst[0].pose.slide_mm, 2999.5);
  EXPECT_EQ(back.worst[0].pose.pan_deg, -35.25);
  EXPECT_EQ(back.worst[0].chi2, 90.0 / 7.0);
  EXPECT_EQ(back.worst[0].scatter_ratio, 1.0 / 3.0);
  EXPECT_EQ(back.worst[0].worst_channel, "dSigma");
  EXPECT_EQ(back.worst[0].worst_residual_percent, -2.0 / 3.0);
  EXPECT_EQ(Emitted(back), text);
}

TEST(ModelFileFitness, RefusesUnknownAndMissingKeys) {
  ExpectRefused(ExampleWith("  poses_over: 2\n", "  poses_over: 2\n  chi: 3\n"), "fitness.chi",
                "unknown key");
  ExpectRefused(ExampleWith("  limit: 1.27\n", ""), "fitness.limit", "missing");
  ExpectRefused(ExampleWith("channel: dE, ", ""), "fitness.worst_poses[1].channel", "missing");
  ExpectRefused(ExampleWith("chi2: 9.1", "chi_2: 9.1"), "fitness.worst_poses[0].chi_2",
                "unknown key");
}

TEST(ModelFileFitness, RefusesValuesOfTheWrongKind) {
  ExpectRefused(ExampleWith("dof: 180", "dof: many"), "fitness.dof", "cannot read 'many'");
  ExpectRefused(ExampleWith("reduced_chi2: 0.93", "reduced_chi2: .nan"), "fitness.reduced_chi2",
                "not a finite number");
  ExpectRefused(ExampleWith("passed: false", "passed: perhaps"), "fitness.passed", "perhaps");
  ExpectRefused(ExampleWith("channels: 3", "channels: 3.5"), "fitness.worst_poses[1].channels",
                "cannot read '3.5'");
  ExpectRefused("fitness:\n  passed: true\n  reduced_chi2: 1\n  dof: 1\n  limit: 1\n"
                "  pose_limit: 1\n  tail_probability: 0.001\n  size_floor: 0\n"
                "  difference_floor: 0\n  poses: 1\n  poses_over: 0\n  cause: \"\"\n"
                "  worst_poses: 3\n",
                "fitness.worst_poses", "expected a sequence");
}

}  // namespace
}  // namespace irdist::model_file
