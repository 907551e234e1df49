#pragma once
// `irdist plan --suggest`: the probe run. Records probe frames at the recipe's two ends on its rig
// (the live run's recording, app/runs/run.h) and proposes the exposures and the current from them
// (the computation in app/runs/suggest.h).

#include <string>

#include "app/inputs/command_args.h"
#include "app/inputs/errors.h"

namespace irdist {

// plan --suggest: records probe frames at the recipe's two ends on its rig and proposes t_r, the
// t_n and the current (app/runs/suggest.h). Throws SuggestError when no exposures fit.
void RunSuggest(const PlanArgs& args, CommandIo io);

struct Recipe;
struct Plan;
// The probe recipe RunSuggest records (YAML written through yaml-cpp's emitter, so any rig path
// or name reads back as it is): the recipe's two ends crossed (nearest distance, smallest angle,
// highest current; farthest, largest angle, lowest current), at its t_r and its longest t_n.
std::string SuggestProbeRecipe(const Recipe& recipe, const Plan& plan);

}  // namespace irdist
