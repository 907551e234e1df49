// Tests of acquisition/pixel_pipeline.h: the table of pixel-shaping features and what counts as
// neutral.
#include "acquisition/pixel_pipeline.h"

#include <gtest/gtest.h>

#include <set>
#include <string>

namespace irdist {
namespace {

TEST(PixelPipeline, TheTableHoldsEveryVendorSpellingOnce) {
  std::set<std::string> seen;
  for (const PixelFeatureSpec& spec : PixelPipelineTable()) {
    EXPECT_FALSE(spec.spellings.empty()) << spec.what;
    for (const char* name : spec.spellings) EXPECT_TRUE(seen.insert(name).second) << name;
  }
  for (const char* name :
       {"GammaEnable", "GammaEnabled", "Gamma", "LUTEnable", "DigitalShift", "BlackLevelAuto",
        "DefectCorrectionEnable", "NoiseReduction", "BinningHorizontalMode"}) {
    EXPECT_EQ(seen.count(name), 1u) << name;
  }
}

TEST(PixelPipeline, NeutralValuesCompareAsTheCameraWritesThem) {
  EXPECT_TRUE(IsNeutralValue("1.000000", "1"));
  EXPECT_TRUE(IsNeutralValue("false", "false"));
  EXPECT_TRUE(IsNeutralValue("0", "false"));
  EXPECT_TRUE(IsNeutralValue("Sum", ""));  // stated only
  EXPECT_FALSE(IsNeutralValue("true", "false"));
  EXPECT_FALSE(IsNeutralValue("0.45", "1"));
  EXPECT_FALSE(IsNeutralValue("Continuous", "Off"));
}

TEST(PixelPipeline, TheSummaryNamesWhatIsNotNeutral) {
  std::vector<PixelFeatureState> states = {
      {"LUT", "LUTEnable", "true", "true", false, "LUTEnable is read-only or locked"},
      {"gamma", "Gamma", "1", "1", true, ""}};
  EXPECT_EQ(NotNeutralSummary(states), "LUTEnable true (LUTEnable is read-only or locked)");
  states[0].neutral = true;
  EXPECT_EQ(NotNeutralSummary(states), "");
}

}  // namespace
}  // namespace irdist
