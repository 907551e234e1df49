#include "app/inputs/track_recipe.h"

#include <gtest/gtest.h>

#include <string>

#include "app/inputs/recipe.h"

namespace irdist {
namespace {

const std::string kRecipes = std::string(IRDIST_SOURCE_DIR) + "/recipes";

TrackRecipe Parse(const std::string& text) { return ParseTrackRecipe(text, "t.yaml", kRecipes); }

// The refusal's text of `text` ("" when it parses).
std::string Refusal(const std::string& text) {
  try {
    Parse(text);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

constexpr char kHead[] = "kind: track\nrig: virtual\ntrack:\n  bias_ma: 490\n  segments:\n";

TEST(TrackRecipeTest, TheShippedTrackRecipeLoadsWithItsSegments) {
  const std::string path = kRecipes + "/track-slide.yaml";
  EXPECT_EQ(RecipeKindOf(path), "track");
  EXPECT_EQ(RecipeKindOf(kRecipes + "/smoke-calibration.yaml"), "sweep");
  const TrackRecipe r = LoadTrackRecipe(path);
  EXPECT_EQ(r.name, "track-slide");
  EXPECT_DOUBLE_EQ(r.bias_ma, 490.0);
  EXPECT_DOUBLE_EQ(r.exposure_ms, 8.0);
  ASSERT_EQ(r.segments.size(), 2u);
  EXPECT_DOUBLE_EQ(r.segments[0].slide_from_mm, 1500.0);
  EXPECT_DOUBLE_EQ(r.segments[0].slide_to_mm, 3000.0);
  EXPECT_DOUBLE_EQ(r.segments[0].speed_mm_s, 300.0);
  EXPECT_DOUBLE_EQ(r.segments[0].pan_speed_deg_s, 0.0);
  EXPECT_DOUBLE_EQ(r.segments[1].pan_from_deg, 0.0);
  EXPECT_DOUBLE_EQ(r.segments[1].pan_to_deg, 20.0);
  EXPECT_DOUBLE_EQ(r.segments[1].pan_speed_deg_s, 10.0);
}

TEST(TrackRecipeTest, ASegmentStandsAtTheTracksPanUnlessItMovesThePan) {
  const TrackRecipe r = Parse(
      "kind: track\nrig: virtual\ntrack:\n  bias_ma: 490\n  pan_deg: 15\n  segments:\n"
      "    - {slide_mm: [2000, 2500], speed_mm_s: 100}\n"
      "    - {slide_mm: 2500, pan_deg: [15, -15], pan_speed_deg_s: 5}\n");
  ASSERT_EQ(r.segments.size(), 2u);
  EXPECT_DOUBLE_EQ(r.segments[0].pan_from_deg, 15.0);
  EXPECT_DOUBLE_EQ(r.segments[0].pan_to_deg, 15.0);
  EXPECT_DOUBLE_EQ(r.segments[1].slide_from_mm, 2500.0);
  EXPECT_DOUBLE_EQ(r.segments[1].speed_mm_s, 0.0);
  EXPECT_EQ(r.segments[1].line, 8);
}

TEST(TrackRecipeTest, BadSegmentsAreRefusedAtTheirLineWithTheFix) {
  const std::string head(kHead);  // segments start on line 6
  EXPECT_NE(Refusal(head + "    - {slide_mm: [1500, 3000]}\n").find("t.yaml:6:"), std::string::npos);
  EXPECT_NE(Refusal(head + "    - {slide_mm: [1500, 3000], speed_mm_s: 0}\n").find("speed_mm_s"),
            std::string::npos);
  EXPECT_NE(Refusal(head + "    - {slide_mm: [1500, 3000], speed_mm_s: 9000}\n")
                .find("slide speed"),
            std::string::npos);
  EXPECT_NE(Refusal(head + "    - {slide_mm: [500, 3000], speed_mm_s: 100}\n")
                .find("station.limits"),
            std::string::npos);
  EXPECT_NE(Refusal(head + "    - {slide_mm: [2000, 2000], speed_mm_s: 100}\n")
                .find("moves nothing"),
            std::string::npos);
  EXPECT_NE(Refusal(head + "    - {slide_mm: 2000, pan_deg: [0, 10]}\n").find("pan_speed_deg_s"),
            std::string::npos);
  EXPECT_NE(Refusal(head + "    - {slide_mm: [1500, 3000], speed_mm_s: 100, sped: 1}\n")
                .find("sped"),
            std::string::npos);
  EXPECT_NE(Refusal(head + "    - {slide_mm: [1500, 3000, 2000], speed_mm_s: 100}\n")
                .find("[from, to]"),
            std::string::npos);
  EXPECT_NE(Refusal("kind: track\nrig: virtual\ntrack:\n  segments: []\n").find("bias_ma"),
            std::string::npos);
  EXPECT_NE(Refusal(head).find("segments"), std::string::npos);
  EXPECT_NE(Refusal("kind: trak\n").find("kind 'trak'"), std::string::npos);
}

TEST(TrackRecipeTest, TheSweepParserSendsATrackRecipeToValidate) {
  try {
    ParseRecipe(std::string(kHead) + "    - {slide_mm: [1500, 3000], speed_mm_s: 100}\n", "t.yaml",
                kRecipes);
    FAIL() << "a track recipe parsed as a sweep";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("irdist validate t.yaml"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace irdist
