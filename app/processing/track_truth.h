#pragma once
// The truth of a track run's frames (docs/recipes.md "Track recipes"): on the virtual rig the
// station's exact trajectory (sim/trajectory.h, logged by `irdist sim` to the file its state file
// names) at the middle of each frame's exposure, with the one-frame Cramer-Rao bound of the rig's
// physics at that pose (app/processing/crb.h); on a real rig the commanded profile (each segment's
// trapezoid from the device's speed and acceleration, started when its move was sent), with the
// recipe's stated uncertainty, and the frame's own standard error as the yardstick (a real rig
// has no physics to bound with).

#include <cstdint>
#include <string>
#include <vector>

#include "app/processing/track_summary.h"

namespace irdist {

// The virtual rig's truth of every row: `trajectory_csv` (sim/trajectory_file.h), the rig file
// (its physics for the bound), the IRED's current and the tilt of the run. Throws InputError
// (a damaged trajectory file), RecipeError (the rig's virtual: section).
std::vector<TrackTruth> VirtualTrackTruths(const std::vector<TrackFrameRow>& rows,
                                           const std::string& trajectory_csv,
                                           const std::string& rig_path, double bias_ma);

// One commanded move of the slide as the run sent it.
struct CommandedMove {
  double from_mm = 0.0, to_mm = 0.0;
  double speed_mm_s = 0.0, accel_mm_s2 = 0.0;
  std::int64_t start_monotonic_ns = 0;  // host monotonic time the move was sent
};

// A real rig's truth of every row: the commanded moves (in time order), a frame's middle of
// exposure taken as its arrival on the host's monotonic clock (`monotonic_ns`, one per row)
// less the readout and half the exposure; `truth_sd_mm` its stated uncertainty. Between moves
// the slide stands at the last move's end.
std::vector<TrackTruth> CommandedTrackTruths(const std::vector<TrackFrameRow>& rows,
                                             const std::vector<std::int64_t>& monotonic_ns,
                                             const std::vector<CommandedMove>& moves,
                                             double readout_ms, double truth_sd_mm);

}  // namespace irdist
