#pragma once
// The live runs behind the irdist commands: calibrate and validate (sweep a recipe on a rig, record,
// then fit or estimate) and plan --suggest (probe frames). The offline commands (fit, playback,
// check) are declared in app/runs/offline.h.
//
// Run folder layout (always the same):
//   DIR/recording/      the recording (docs/recording-format.md)
//   DIR/station.log     every line sent to and received from the station
//   DIR/features.csv    per-frame features (docs/reports.md)
//   DIR/model.yaml      calibrate: the calibration (docs/estimator.md)
//   DIR/estimates.csv   validate: per-bracket estimates; DIR/summary.yaml: the figures
//   DIR/report/index.html
// A resumed run keeps the earlier sessions' station logs as station.<n>.log.

#include <string>

#include "app/cli/command_args.h"
#include "app/cli/errors.h"

namespace irdist {

// Throw InterruptedError after a Ctrl-C (recording closed as cut), RecipeError, CameraError,
// LinkError, StationError, RecordingError, ModelFileError.
void RunCalibrate(const CalibrateArgs& args, CommandIo io);
void RunValidate(const ValidateArgs& args, CommandIo io);
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
