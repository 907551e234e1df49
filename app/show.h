#pragma once
// Playback's `--show` window (app/show.cc).

#include <cstdint>
#include <map>
#include <vector>

#include "app/summary.h"
#include "base/check.h"
#include "estimator/features.h"

namespace irdist {

class RecordingReader;

// An OpenCV window stepping through the recording's frames with the ROI, the ellipse and the
// bracket's estimate drawn (any key: next frame, q or Esc: quit). Throws CameraError-free
// irdist::Error (DisplayError) when no display is available.
// `features` by frame index (app/offline.h's FeatureMap).
void ShowPlayback(const RecordingReader& reader, const std::map<std::int64_t, Features>& features,
                  const std::vector<EstimateRow>& estimates);

class DisplayError : public Error {
 public:
  using Error::Error;
};

}  // namespace irdist
