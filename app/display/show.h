#pragma once
// The display side of the app (app/display/show.cc): playback's `--show` window, and the window
// helpers that `irdist view` shares with it (both draw with app/display/view_layout.h).

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "app/processing/estimates_csv.h"
#include "base/check.h"
#include "estimator/features.h"

namespace irdist {

class RecordingReader;

// An OpenCV window stepping through the recording's frames with the ROI, the ellipse and the
// bracket's estimate drawn (any key: next frame, q or Esc: quit). Throws CameraError-free
// irdist::Error (DisplayError) when no display is available.
// `features` by frame index (app/processing/frame_features.h's FeatureMap).
void ShowPlayback(const RecordingReader& reader, const std::map<std::int64_t, Features>& features,
                  const std::vector<EstimateRow>& estimates);

class DisplayError : public Error {
 public:
  using Error::Error;
};

// Throws DisplayError (naming `what`) when neither DISPLAY nor WAYLAND_DISPLAY is set.
void RequireDisplay(const std::string& what);
// cv::namedWindow; throws DisplayError when OpenCV cannot open it.
void OpenWindow(const std::string& window, const std::string& what);
}  // namespace irdist
