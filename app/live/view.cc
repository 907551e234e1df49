#include "app/live/view.h"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <opencv2/highgui.hpp>
#include <optional>
#include <ostream>
#include <sstream>
#include <utility>

#include "app/display/show.h"
#include "app/display/view_layout.h"
#include "app/live/live_camera.h"
#include "app/live/measure.h"
#include "app/live/png_output.h"
#include "app/live/single_exposure.h"
#include "app/processing/frame_features.h"
#include "estimator/model_file.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;

// What the window shows of one frame.
struct ViewFrame {
  cv::Mat image;
  Features features;
  std::optional<cv::Rect> roi;  // the rig's ROI drawn on a whole-sensor frame
  FocusFigure focus;
  std::vector<std::string> lines;
};

constexpr const char* kKeysLine =
    "keys: q or Esc quit, w whole sensor / ROI, s save a screenshot (view-N.png)";

// The rig's roi_px, in the whole sensor's pixels.
cv::Rect RigRoi(const Rig& rig) {
  const CameraConfig& c = rig.camera;
  return {c.roi_offset_x, c.roi_offset_y, c.roi_width, c.roi_height};
}

// Which region is shown, and how to switch.
std::string RegionLine(const Rig& rig, const cv::Mat& image, bool whole) {
  std::ostringstream line;
  if (rig.camera.FullFrame()) {
    line << "whole sensor " << image.cols << " x " << image.rows << " px (the rig has no roi_px)";
  } else if (whole) {
    const cv::Rect r = RigRoi(rig);
    line << "whole sensor " << image.cols << " x " << image.rows << " px, the rig's roi_px ["
         << r.x << ", " << r.y << ", " << r.width << ", " << r.height
         << "] in cyan (w: back to the ROI)";
  } else {
    const cv::Rect r = RigRoi(rig);
    line << "roi_px [" << r.x << ", " << r.y << ", " << r.width << ", " << r.height
         << "] (w: the whole sensor, to aim)";
  }
  return line.str();
}

// The saturation advice (none when no pixel saturates); `remedy` is the flag that helps.
std::string SaturationLine(const Features& f, const std::string& remedy) {
  if (f.saturated_pixels == 0) return "";
  return std::to_string(f.saturated_pixels) + " saturated pixels (magenta): " + remedy;
}

// Where view's frames come from, ROI or whole sensor: single exposures without a model; with one,
// the live estimate on the ROI and single exposures (estimates paused) on the whole sensor.
class ViewSource {
 public:
  ViewSource(LiveCamera& live, double exposure_ms, MeasureSession* session,
             const CalibrationModel* model, std::ostream& notices)
      : live_(live), single_(live, exposure_ms, notices), session_(session),
        focus_(model != nullptr ? &model->blur_calibration : nullptr) {}
  void SetWholeSensor(bool whole) {
    if (live_.rig().camera.FullFrame()) return;  // nothing to toggle
    live_.SetWholeSensor(whole);
    whole_ = whole;
  }
  ViewFrame Next(double exposure_ms) {
    ViewFrame frame;
    if (session_ != nullptr && !whole_) {
      const MeasureSample s = session_->Next(Elapsed());
      frame.image = session_->last_image();
      frame.features = session_->last_features();
      frame.lines.push_back(MeasureLine(s));
      if (s.have_estimate && s.estimate.ok) last_d_mm_ = s.estimate.d_mm;
    } else {
      frame.image = single_.Next();
      frame.features = FrameFeatures(frame.image, live_.bit_depth(), FeatureOptions{});
      char exposure[96];
      std::snprintf(exposure, sizeof(exposure), "exposure %.3g ms%s", exposure_ms,
                    session_ != nullptr ? " (estimates paused on the whole sensor)" : "");
      frame.lines.push_back(exposure);
    }
    if (whole_) frame.roi = RigRoi(live_.rig());
    // The blur does not depend on the exposure: the last estimate's distance serves the whole
    // sensor's frames too.
    frame.focus = focus_.Add(frame.features, last_d_mm_);
    frame.lines.push_back(RegionLine(live_.rig(), frame.image, whole_));
    frame.lines.push_back(LevelLine(frame.features));
    const std::string saturated = SaturationLine(
        frame.features, session_ != nullptr && !whole_ ? "lower the IRED's current"
                                                       : "shorten --exposure-ms or lower the "
                                                         "IRED's current");
    if (!saturated.empty()) frame.lines.push_back(saturated);
    frame.lines.push_back(frame.focus.Line());
    return frame;
  }

 private:
  double Elapsed() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
  }
  LiveCamera& live_;
  SingleExposure single_;
  MeasureSession* session_;
  FocusTracker focus_;
  bool whole_ = false;
  double last_d_mm_ = 0.0;  // the last estimate's distance (0: none yet)
  std::chrono::steady_clock::time_point t0_ = std::chrono::steady_clock::now();
};

// The window's drawable size (0 x 0 where the backend does not report it).
cv::Size WindowImageSize(const std::string& window) {
  try {
    return cv::getWindowImageRect(window).size();
  } catch (const cv::Exception&) {
    return {};  // not every backend reports it
  }
}

// The size view lays its image out to: 1024 x 720 at first, then the window's size once the user
// resizes it (a change of the window's size between two frames that view did not ask for).
class WindowFit {
 public:
  explicit WindowFit(std::string window) : window_(std::move(window)) {}
  cv::Size Target() const { return target_; }
  // After a frame is shown (`shown`, its image) and the window's events are handled.
  void Shown(const cv::Mat& shown) {
    if (frames_++ == 0) {
      cv::resizeWindow(window_, shown.cols, shown.rows);
      return;
    }
    const cv::Size now = WindowImageSize(window_);
    if (now.width >= 320 && now.height >= 240 && seen_.area() > 0 && now != seen_) target_ = now;
    seen_ = now;
  }

 private:
  std::string window_;
  cv::Size target_{1024, 720};
  cv::Size seen_;
  int frames_ = 0;
};

// Saves `shown` as the next view-N.png that does not exist (none is replaced).
void SaveNumbered(const cv::Mat& shown, int* saved, std::ostream& out) {
  std::string file;
  std::error_code ec;
  do {
    file = "view-" + std::to_string((*saved)++) + ".png";
  } while (fs::exists(fs::symlink_status(file, ec)));
  WritePng(file, shown, "screenshot");
  out << "Saved " << file << "\n";
}

// Shows frames until q/Esc, or `frames` frames; saves the last view to `screenshot`.
void ViewLoop(ViewSource& source, int bit_depth, const ViewArgs& args, std::ostream& out) {
  const std::string window = "irdist view";
  OpenWindow(window, "view");
  WindowFit fit(window);
  bool whole = args.whole_sensor;
  source.SetWholeSensor(whole);
  cv::Mat shown;
  std::vector<std::string> last_lines;
  int saved = 0;
  for (int n = 0; args.frames <= 0 || n < args.frames; ++n) {
    ViewFrame frame = source.Next(args.exposure_ms);
    last_lines = frame.lines;
    frame.lines.push_back(kKeysLine);
    const ViewPanel panel{frame.image, bit_depth, &frame.features, frame.roi, frame.focus,
                          frame.lines};
    shown = ComposeView(panel, fit.Target());
    cv::imshow(window, shown);
    const int key = cv::waitKey(1);
    fit.Shown(shown);
    if (key == 'q' || key == 27) break;
    if (key == 'w') source.SetWholeSensor(whole = !whole);
    if (key == 's') SaveNumbered(shown, &saved, out);
  }
  if (!args.screenshot.empty() && !shown.empty()) WritePng(args.screenshot, shown, "screenshot");
  cv::destroyWindow(window);
  // What the last frame showed, for the terminal (and a log): estimate, region, level, focus.
  for (const std::string& line : last_lines) out << line << "\n";
}

}  // namespace

void RunView(const ViewArgs& args, CommandIo io) {
  RequireValid(args, "view");
  if (!args.screenshot.empty()) CheckPngOutput(args.screenshot, args.force, "--screenshot");
  RequireDisplay("view");
  if (!args.model.empty()) {
    const CalibrationModel model = LoadModel(args.model);
    MeasureArgs measure;
    measure.model = args.model;
    measure.rig = args.rig;
    measure.at = args.at;
    measure.time_scale = args.time_scale;
    MeasureSession session(measure, model, io, /*quiet_rig=*/true);
    ViewSource source(session.live(), args.exposure_ms, &session, &model, io.err);
    ViewLoop(source, session.bit_depth(), args, io.out);
    source.SetWholeSensor(false);
    session.Finish();
    return;
  }
  const std::unique_ptr<LiveCamera> live =
      OpenForSingleExposures(args.rig, args.at, args.exposure_ms, args.time_scale, io.err);
  ViewSource source(*live, args.exposure_ms, nullptr, nullptr, io.err);
  ViewLoop(source, live->bit_depth(), args, io.out);
}

}  // namespace irdist
