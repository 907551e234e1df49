#include "app/runs/plan_command.h"

#include <gtest/gtest.h>

#include <sstream>
#include <string>

#include "app/inputs/errors.h"

namespace irdist {
namespace {

const std::string kSmoke = std::string(IRDIST_SOURCE_DIR) + "/recipes/smoke-calibration.yaml";

// The lines of `text` that are pose rows of the order (they start with spaces and an index).
int PoseRows(const std::string& text) {
  std::istringstream in(text);
  std::string line;
  int rows = 0;
  bool in_order = false;
  while (std::getline(in, line)) {
    if (line.rfind("Order (", 0) == 0) {
      in_order = true;
      continue;
    }
    if (in_order && line.find("slide_mm") == std::string::npos && !line.empty()) ++rows;
  }
  return rows;
}

std::string Plan(int show_poses) {
  PlanArgs args;
  args.recipe = kSmoke;
  args.show_poses = show_poses;
  std::ostringstream out, err;
  RunPlan(args, {out, err});
  return out.str();
}

// The smoke recipe: 3 distances x 4 angles x 2 currents = 24 poses; its rig, output and bracket
// said as the recipe has them, and as many pose rows as asked.
TEST(PlanCommand, PrintsTheRecipeTheBracketAndTheAskedPoses) {
  const std::string text = Plan(3);
  EXPECT_NE(text.find("Recipe: " + kSmoke + " (smoke-calibration)"), std::string::npos) << text;
  EXPECT_NE(text.find("Rig: virtual"), std::string::npos) << text;
  EXPECT_NE(text.find("Bracket: t_ref 8 ms; t_meas 30, 33, 36 ms"), std::string::npos) << text;
  EXPECT_NE(text.find("Order (first 3 of 24 poses):"), std::string::npos) << text;
  EXPECT_EQ(PoseRows(text), 3) << text;
}

TEST(PlanCommand, AllPosesOrNone) {
  const std::string all = Plan(-1);
  EXPECT_NE(all.find("Order (all 24 poses):"), std::string::npos) << all;
  EXPECT_EQ(PoseRows(all), 24) << all;
  const std::string none = Plan(0);
  EXPECT_EQ(none.find("Order ("), std::string::npos) << none;
  EXPECT_NE(none.find("Bracket: "), std::string::npos) << none;
}

TEST(PlanCommand, AMissingRecipeIsARecipeErrorNamingIt) {
  PlanArgs args;
  args.recipe = "/nonexistent/recipe.yaml";
  std::ostringstream out, err;
  try {
    RunPlan(args, {out, err});
    ADD_FAILURE() << "no error";
  } catch (const RecipeError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/recipe.yaml"), std::string::npos)
        << e.what();
  }
  EXPECT_TRUE(out.str().empty()) << out.str();
}

}  // namespace
}  // namespace irdist
