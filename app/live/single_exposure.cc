#include "app/live/single_exposure.h"

#include <chrono>
#include <cstdio>
#include <ostream>

#include "acquisition/camera.h"

namespace irdist {

std::unique_ptr<LiveCamera> OpenForSingleExposures(const std::string& rig,
                                                   const std::vector<double>& at,
                                                   double exposure_ms, double time_scale,
                                                   std::ostream& err) {
  LiveCameraOptions options;
  options.rig_spec = rig;
  options.at = at;
  options.time_scale = time_scale;
  options.first_exposure_us = exposure_ms * 1000.0;
  options.longest_exposure_us = exposure_ms * 1000.0;
  return std::make_unique<LiveCamera>(options, err);
}

SingleExposure::SingleExposure(LiveCamera& live, double exposure_ms, std::ostream& notices)
    : live_(live) {
  BracketOptions bracket;
  // BracketCapture takes a reference and at least one measurement: two frames at the same
  // exposure, the second one shown (it also skips a first frame after an idle stream).
  bracket.exposures_us = {exposure_ms * 1000.0, exposure_ms * 1000.0};
  bracket.trigger_source = live.trigger_source();
  bracket.frame_timeout = std::chrono::milliseconds(live.frame_timeout_ms());
  // A camera whose exposure chunks stop coming: read-backs from then on, said once (on the
  // command's diagnostics stream, which outlives the capture).
  std::ostream* out = &notices;
  bracket.on_notice = [out](const std::string& text) { *out << "warning: " << text << "\n"; };
  capture_ = std::make_unique<BracketCapture>(live.camera(), bracket);
}

cv::Mat SingleExposure::Next() {
  BracketResult result = capture_->Capture(live_.Trigger());
  if (!result.complete) result = capture_->Capture(live_.Trigger());
  if (!result.complete) throw CameraError("no frame twice: " + result.failure);
  return result.frames.back().image;
}

std::string LevelLine(const Features& f) {
  char text[160];
  std::snprintf(text, sizeof(text), "peak %.1f%% of full scale, background %.2f%%, saturated px %d",
                100.0 * f.peak, 100.0 * f.background, f.saturated_pixels);
  return text;
}

}  // namespace irdist
