// playback --show: an OpenCV window over the recording's frames.
#include <algorithm>
#include <cstdlib>
#include <map>
#include <opencv2/highgui.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "acquisition/recording_reader.h"
#include "app/display/show.h"
#include "app/display/view_layout.h"

namespace irdist {

void RequireDisplay(const std::string& what) {
  const char* display =
      std::getenv("DISPLAY");  // NOLINT(concurrency-mt-unsafe): read once, nobody sets it
  const char* wayland = std::getenv("WAYLAND_DISPLAY");  // NOLINT(concurrency-mt-unsafe)
  if ((display == nullptr || *display == '\0') && (wayland == nullptr || *wayland == '\0')) {
    throw DisplayError(what +
                       " needs a display (DISPLAY or WAYLAND_DISPLAY is not set); run it in a "
                       "desktop session, with X forwarding (ssh -X) or under Xvfb.");
  }
}

void OpenWindow(const std::string& window, const std::string& what) {
  try {
    // Resizable, the image scaled to the window, no toolbar or status bar taking its room.
    cv::namedWindow(window, cv::WINDOW_NORMAL | cv::WINDOW_KEEPRATIO | cv::WINDOW_GUI_NORMAL);
  } catch (const cv::Exception& e) {
    throw DisplayError(what + ": cannot open a window: " + e.what());
  }
}

void ShowPlayback(const RecordingReader& reader,
                  const std::map<std::int64_t, Features>& features,
                  const std::vector<EstimateRow>& estimates) {
  RequireDisplay("--show");
  std::map<int, const EstimateRow*> joint;
  for (const EstimateRow& row : estimates) {
    if (row.method == "i0_free" && row.dt_ms == 0.0) joint[row.bracket] = &row;
  }
  const std::string window = "irdist playback";
  OpenWindow(window, "--show");
  for (const FrameRecord& row : reader.rows()) {
    const auto f = features.find(row.index);
    std::ostringstream text;
    text << row.file << " bracket " << row.bracket_id << " " << FrameRoleName(row.role) << " "
         << row.requested_exposure_us / 1000.0 << " ms, true d " << row.slide_mm << " mm";
    const auto est = joint.find(static_cast<int>(row.bracket_id));
    if (est != joint.end() && est->second->ok) {
      text << ", estimate " << est->second->d_mm << " mm, theta " << est->second->theta_deg;
    }
    ViewPanel panel;  // view's layout: saturated pixels, a zoom, text wrapped to the window
    panel.image = reader.LoadImage(row);
    panel.bit_depth = reader.header().bit_depth;
    panel.features = f != features.end() ? &f->second : nullptr;
    panel.lines = {text.str(), "any key: next frame, q or Esc: quit"};
    cv::imshow(window, ComposeView(panel, {1024, 720}));
    const int key = cv::waitKey(0);
    if (key == 'q' || key == 27) break;
  }
  cv::destroyWindow(window);
}

}  // namespace irdist
