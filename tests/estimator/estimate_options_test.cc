// EstimateOptions: the defaults are valid, every bad value is refused naming its field, the
// paper's set is Algorithm 1 as published, and each choice has its one name (model files and
// summary.yaml carry them).
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "estimator/estimate.h"

namespace irdist {
namespace {

TEST(EstimateOptionsTest, TheDefaultsAndThePapersSetAreValid) {
  std::string why;
  EXPECT_TRUE(EstimateOptions().IsValid(&why)) << why;
  EXPECT_TRUE(PaperEstimateOptions().IsValid(&why)) << why;
}

TEST(EstimateOptionsTest, EachBadValueIsRefusedNamingItsField) {
  struct Bad {
    const char* field;
    std::function<void(EstimateOptions*)> set;
  };
  const std::vector<Bad> bad = {
      {"max_iterations", [](EstimateOptions* o) { o->max_iterations = 0; }},
      {"step_tolerance", [](EstimateOptions* o) { o->step_tolerance = 0.0; }},
      {"step_tolerance", [](EstimateOptions* o) { o->step_tolerance = NAN; }},
      {"range_margin", [](EstimateOptions* o) { o->range_margin = -0.1; }},
      {"theta_prior_sd_deg", [](EstimateOptions* o) { o->theta_prior_sd_deg = 0.0; }},
      {"radiometric_weight", [](EstimateOptions* o) { o->radiometric_weight = 0.0; }},
      {"geometric_weight", [](EstimateOptions* o) { o->geometric_weight = -1.0; }},
      {"radiometric_huber", [](EstimateOptions* o) { o->radiometric_huber = NAN; }},
  };
  for (const Bad& b : bad) {
    EstimateOptions options;
    b.set(&options);
    std::string why;
    EXPECT_FALSE(options.IsValid(&why)) << b.field;
    EXPECT_EQ(why.rfind(b.field, 0), 0u) << why;
    EXPECT_FALSE(options.IsValid(nullptr)) << b.field;  // no reason asked for
  }
  EstimateOptions edge;  // the bounds themselves are allowed
  edge.max_iterations = 1;
  edge.range_margin = 0.0;
  edge.geometric_weight = 0.0;
  edge.radiometric_huber = 0.0;
  EXPECT_TRUE(edge.IsValid(nullptr));
}

TEST(EstimateOptionsTest, ThePapersSetIsAlgorithm1FromTheFeatures) {
  const EstimateOptions paper = PaperEstimateOptions();
  EXPECT_EQ(paper.method, EstimateMethod::kAlgorithm1);
  EXPECT_EQ(paper.theta_source, ThetaSource::kFeatures);
  EXPECT_EQ(paper.tie_breaker, RootTieBreaker::kResidualVote);
  EXPECT_FALSE(paper.theta_correction);
}

TEST(EstimateOptionsTest, EachChoiceHasItsName) {
  EXPECT_STREQ(ToString(EstimateMethod::kAlgorithm1), "algorithm1");
  EXPECT_STREQ(ToString(EstimateMethod::kFused), "fused");
  EXPECT_STREQ(ToString(ThetaSource::kFeatures), "features");
  EXPECT_STREQ(ToString(ThetaSource::kCalibratedBlur), "calibrated_blur");
  EXPECT_STREQ(ToString(ThetaSource::kBracketMoments), "bracket_moments");
  EXPECT_STREQ(ToString(RootTieBreaker::kResidualVote), "residual_vote");
  EXPECT_STREQ(ToString(RootTieBreaker::kGeometric), "geometric");
}

}  // namespace
}  // namespace irdist
