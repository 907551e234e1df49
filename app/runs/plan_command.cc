#include "app/runs/plan_command.h"

#include <algorithm>
#include <cstdio>
#include <ostream>
#include <sstream>
#include <string>
#include <vector>

#include "app/inputs/recipe.h"
#include "app/inputs/rig.h"
#include "app/runs/run_suggest.h"
#include "sim/rig_physics.h"
#include "station/plan.h"

namespace irdist {
namespace {

std::string JoinMs(const std::vector<double>& values) {
  std::ostringstream out;
  for (size_t i = 0; i < values.size(); ++i) out << (i > 0 ? ", " : "") << values[i];
  return out.str();
}

void PrintPlan(const Recipe& recipe, const Plan& plan, int show_poses, std::ostream& out) {
  out << "Recipe: " << recipe.path << " (" << recipe.name << ")";
  if (!recipe.description.empty()) out << ": " << recipe.description;
  out << "\nRig: " << recipe.rig.name << " (" << recipe.rig_path << ")\n";
  out << "Output: " << recipe.output_dir
      << "; after recording: " << AfterRecordingName(recipe.after) << "\n";
  const BracketSpec& bracket = recipe.sweep.bracket;
  out << "Bracket: t_ref " << bracket.t_ref_ms << " ms; t_meas " << JoinMs(bracket.t_meas_ms)
      << " ms; " << bracket.repeats << (bracket.repeats == 1 ? " repeat" : " repeats")
      << "; reference " << (bracket.retake_reference ? "retaken before each t_meas" : "taken once")
      << "\n";
  out << plan.summary.BriefReport() << "\n";
  const int total = static_cast<int>(plan.poses.size());
  const int shown = show_poses < 0 ? total : std::min(show_poses, total);
  if (shown == 0) return;
  out << "Order ("
      << (shown == total ? "all " + std::to_string(total)
                         : "first " + std::to_string(shown) + " of " + std::to_string(total))
      << " poses):\n";
  out << "      #  slide_mm   pan_deg  tilt_deg theta_deg   bias_ma  repeat\n";
  for (int i = 0; i < shown; ++i) {
    const Pose& p = plan.poses[static_cast<size_t>(i)];
    char line[160];
    std::snprintf(line, sizeof(line), "  %5lld %9.2f %9.2f %9.2f %9.2f %9.2f %7d\n",
                  static_cast<long long>(p.index), p.slide_mm, p.pan_deg, p.tilt_deg, p.theta_deg,
                  p.bias_ma, p.repeat);
    out << line;
  }
}

}  // namespace

void RunPlan(const PlanArgs& args, CommandIo io) {
  RequireValid(args, "plan");
  if (args.suggest) {
    RunSuggest(args, io);
    return;
  }
  const Recipe recipe = LoadRecipe(args.recipe);
  PrintRigNotes(recipe.rig, io.err);
  // The rig exactly as sim and calibrate load it: a virtual rig's physics too (its refusals,
  // e.g. a crosstalk of NaN or 5.0001, at file:line:column before any plan is printed).
  if (recipe.rig.kind == RigKind::kVirtual) sim::LoadRigPhysics(recipe.rig_path);
  PrintPlan(recipe, PlanRecipe(recipe), args.show_poses, io.out);
}

}  // namespace irdist
