#pragma once
// `irdist validate TRACK_RECIPE --model M` (docs/recipes.md "Track recipes"): a track recipe's
// run. The station goes through the recipe's profile (each segment: to its start at the
// station's own speed, the recipe's settle, then the move at the segment's cruise speed, set
// through the device's protocol, Motion::SetSpeed) while the camera tracks every frame as
// `measure --track` does (app/live/track_session.h: one exposure, the newest frame estimated,
// the constant-velocity filter). Every frame's row goes to DIR/track.csv as it is estimated;
// at the end DIR/summary.yaml holds the per-frame errors against the truth and the one-frame
// bound, and the filter's velocity against the truth (app/processing/track_summary.h, the truth
// from app/processing/track_truth.h). Ctrl-C stops the station where it is (each motion device's
// controlled stop, Station::MoveToUnless) and keeps what was taken (track.csv, a summary marked
// cut). A track run is not resumable: --resume is refused (the
// motion is one continuous profile; run it again into a new folder).
//
// Lives in app/live/ (not app/runs/) because it reuses the track session, and runs/ is below
// live/ in the app's floors.
//
// On the virtual rig the run uses the running `irdist sim` of the recipe's rig (its station and
// camera; the trajectory file its state file names is the truth); without one it is refused with
// the command that starts it.

#include "app/inputs/command_args.h"

namespace irdist {

// Throws UsageError (--resume, no running sim of a virtual rig), RecipeError, RunFolderError (an
// existing folder), CameraError, StationError, DeviceError, LinkError, InterruptedError (after a
// Ctrl-C, once track.csv and summary.yaml are written).
void RunTrackRecipe(const ValidateArgs& args, CommandIo io);

// `irdist validate`: RunTrackRecipe for a recipe of kind track, else the validation sweep
// (RunValidate, app/runs/run.h).
void RunValidateOrTrack(const ValidateArgs& args, CommandIo io);

}  // namespace irdist
