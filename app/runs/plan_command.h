#pragma once
// `irdist plan RECIPE`: the recipe checked as a run would load it (its rig's physics too, for a
// virtual rig) and its plan printed: rig, output, bracket, the plan's brief report (grid, frame
// count, duration estimate) and the poses in order. `plan --suggest` goes to RunSuggest
// (app/runs/run_suggest.h). Nothing is opened or moved.

#include "app/inputs/command_args.h"

namespace irdist {

void RunPlan(const PlanArgs& args, CommandIo io);

}  // namespace irdist
