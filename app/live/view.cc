#include "app/live/view.h"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cctype>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <iostream>
#include <memory>
#include <optional>
#include <opencv2/highgui.hpp>
#include <opencv2/imgcodecs.hpp>
#include <ostream>
#include <sstream>
#include <utility>

#include "acquisition/bracket.h"
#include "app/inputs/errors.h"
#include "app/display/show.h"
#include "app/display/view_layout.h"
#include "app/live/live_camera.h"
#include "app/live/measure.h"
#include "app/processing/frame_features.h"
#include "base/safe_file.h"
#include "estimator/model_file.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;

// An output image named by `flag`: a .png (the only format that keeps 16-bit values), not an
// existing file unless `force`, never a symbolic link. Checked before the camera starts.
void CheckPngOutput(const std::string& path, bool force, const char* flag) {
  std::string extension = fs::path(path).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (extension != ".png") {
    throw UsageError(std::string(flag) + " " + path + ": irdist writes PNG images only (the one "
                     "supported format: .png, which keeps every bit of the frame); name the "
                     "file FILE.png.");
  }
  std::error_code ec;
  const fs::file_status status = fs::symlink_status(path, ec);
  if (fs::is_symlink(status)) {
    throw RunFolderError(path + " is a symbolic link; irdist never writes through one. Remove it "
                         "or choose another " + flag + " name.");
  }
  if (fs::exists(status) && !force) {
    throw RunFolderError(path + " exists: irdist does not replace a file unasked. Choose another " +
                         std::string(flag) + " name, or add --force to replace it.");
  }
  // The folder is checked now, before the camera starts or the station moves.
  const fs::path parent = fs::path(path).has_parent_path() ? fs::path(path).parent_path() : ".";
  if (!fs::is_directory(parent, ec)) {
    throw RunFolderError(std::string(flag) + " " + path + ": the folder " + parent.string() +
                         " does not exist (or is not a folder); create it first or choose "
                         "another " + flag + ".");
  }
  if (::access(parent.c_str(), W_OK) != 0) {
    throw RunFolderError(std::string(flag) + " " + path + ": cannot write in " + parent.string() +
                         " (" + std::strerror(errno) + "); choose another " + flag + ".");
  }
}

// `image` as a PNG at `path`, written whole (a temporary file renamed into place).
void WritePng(const std::string& path, const cv::Mat& image, const char* what) {
  std::vector<uchar> png;
  std::string why = "cannot be encoded as PNG";
  if (!cv::imencode(".png", image, png) ||
      !WriteFileAtomically(path, std::string_view(reinterpret_cast<const char*>(png.data()),
                                                  png.size()), 0644, &why)) {
    throw RunFolderError(path + ": cannot write the " + what + ": " + why + "; check the folder.");
  }
}

// The side of the suggested region of interest: the features' window with room to move.
constexpr int kSuggestedRoiSidePx = 256;

// The rig's camera opened for single exposures of `exposure_ms` (snap, view without a model).
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

// One exposure after another on a live camera (snap, view without a model, view's whole sensor).
class SingleExposure {
 public:
  SingleExposure(LiveCamera& live, double exposure_ms) : live_(live) {
    BracketOptions bracket;
    // BracketCapture takes a reference and at least one measurement: two frames at the same
    // exposure, the second one shown (it also skips a first frame after an idle stream).
    bracket.exposures_us = {exposure_ms * 1000.0, exposure_ms * 1000.0};
    bracket.trigger_source = live.trigger_source();
    bracket.frame_timeout = std::chrono::milliseconds(live.frame_timeout_ms());
    // A camera whose exposure chunks stop coming: read-backs from then on, said once.
    bracket.on_notice = [](const std::string& text) { std::cerr << "warning: " << text << "\n"; };
    capture_ = std::make_unique<BracketCapture>(live.camera(), bracket);
  }
  cv::Mat Next() {
    BracketResult result = capture_->Capture(live_.Trigger());
    if (!result.complete) result = capture_->Capture(live_.Trigger());
    if (!result.complete) throw CameraError("no frame twice: " + result.failure);
    return result.frames.back().image;
  }

 private:
  LiveCamera& live_;
  std::unique_ptr<BracketCapture> capture_;
};

// The signal line: peak and background as fractions of full scale, saturated pixels.
std::string LevelLine(const Features& f) {
  char text[160];
  std::snprintf(text, sizeof(text), "peak %.1f%% of full scale, background %.2f%%, saturated px %d",
                100.0 * f.peak, 100.0 * f.background, f.saturated_pixels);
  return text;
}

// Where snap looked: the rig's roi_px with its numbers (sensor pixels), or the whole sensor.
std::string WhereLooked(const Rig& rig, const cv::Mat& image) {
  std::ostringstream where;
  if (rig.camera.FullFrame()) {
    where << "the whole sensor (" << image.cols << " x " << image.rows << " px)";
  } else {
    where << "the rig's roi_px [" << rig.camera.roi_offset_x << ", " << rig.camera.roi_offset_y
          << ", " << rig.camera.roi_width << ", " << rig.camera.roi_height << "] (" << rig.path
          << ")";
  }
  return where.str();
}

void PrintNoBlob(const Rig& rig, const cv::Mat& image, int bit_depth, double exposure_ms,
                 std::ostream& out) {
  out << "No blob found in " << WhereLooked(rig, image) << ": is the IRED in view and on (on a "
      << "virtual rig: snap --at SLIDE_MM,PAN_DEG,TILT_DEG,BIAS_MA, or 'irdist station' with "
      << "'irdist sim' running)?\n";
  if (!rig.camera.FullFrame()) {
    out << "To widen it: remove camera.roi_px from " << rig.path
        << " (absent = the whole sensor), snap again, and put the suggested roi_px in.\n";
  }
  double max_level = 0.0;
  cv::minMaxLoc(image, nullptr, &max_level);
  const double max_percent = 100.0 * max_level / FullScale(bit_depth);
  if (max_percent < 10.0) {
    char text[160];
    std::snprintf(text, sizeof(text),
                  "The brightest pixel is %.1f%% of full scale: try a longer --exposure-ms than "
                  "%g.\n",
                  max_percent, exposure_ms);
    out << text;
  }
}

void PrintSnap(const Features& f, const Rig& rig, const cv::Mat& image, double exposure_ms,
               std::ostream& out) {
  if (!f.blob_found) {
    PrintNoBlob(rig, image, f.bit_depth, exposure_ms, out);
    return;
  }
  const double x = f.centroid_px.x + rig.camera.roi_offset_x;
  const double y = f.centroid_px.y + rig.camera.roi_offset_y;
  const int half = kSuggestedRoiSidePx / 2;
  out << "Blob at (" << x << ", " << y << ") sensor px\n";
  // Centred on the blob: its pixel-edge coordinate (x + 0.5) rounded, minus half a side.
  out << "Suggested roi_px: [" << std::max(0, static_cast<int>(std::lround(x + 0.5)) - half)
      << ", " << std::max(0, static_cast<int>(std::lround(y + 0.5)) - half) << ", "
      << kSuggestedRoiSidePx
      << ", " << kSuggestedRoiSidePx << "]\n";
}

// FILE.png -> FILE.preview.png (a name without .png gets .preview.png appended).
std::string PreviewPath(const std::string& out) {
  const std::string ext = ".png";
  const bool has_ext = out.size() > ext.size() &&
                       out.compare(out.size() - ext.size(), ext.size(), ext) == 0;
  return (has_ext ? out.substr(0, out.size() - ext.size()) : out) + ".preview.png";
}

// The frame for people: 8 bit, black = the background, white = the brightest pixel (the
// saturation level when pixels saturate), so a 12-bit frame does not look black in a viewer.
cv::Mat PreviewImage(const cv::Mat& image, const Features& f, int bit_depth) {
  double min_level = 0.0, max_level = 0.0;
  cv::minMaxLoc(image, &min_level, &max_level);
  const double black = std::clamp(f.background * FullScale(bit_depth), min_level, max_level);
  const double span = std::max(1.0, max_level - black);
  cv::Mat preview;
  image.convertTo(preview, CV_8U, 255.0 / span, -black * 255.0 / span);
  return preview;
}

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
             const CalibrationModel* model)
      : live_(live), single_(live, exposure_ms), session_(session),
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

// The camera's refusal of the exposure, in snap's terms (its exposure is --exposure-ms).
cv::Mat SnapFrame(const SnapArgs& args, std::ostream& err, std::unique_ptr<LiveCamera>* live) {
  try {
    *live = OpenForSingleExposures(args.rig, args.at, args.exposure_ms, args.time_scale, err);
    return SingleExposure(**live, args.exposure_ms).Next();
  } catch (const CameraError& e) {
    const std::string what = e.what();
    if (what.find("exposure") == std::string::npos) throw;
    std::ostringstream text;
    text << what.substr(0, what.find("; change")) << "; snap's exposure is --exposure-ms (now "
         << args.exposure_ms << " ms): pass one within the camera's range.";
    throw CameraError(text.str());
  }
}

}  // namespace

void RunSnap(const SnapArgs& args, CommandIo io) {
  const std::string preview = PreviewPath(args.out);
  CheckPngOutput(args.out, args.force, "--out");
  CheckPngOutput(preview, args.force, "--out (its preview)");
  std::unique_ptr<LiveCamera> live;
  const cv::Mat image = SnapFrame(args, io.err, &live);
  WritePng(args.out, image, "frame");
  const int bit_depth = live->bit_depth();
  const Features f = FrameFeatures(image, bit_depth, FeatureOptions{});
  WritePng(preview, PreviewImage(image, f, bit_depth), "preview");
  io.out << "Frame: " << args.out << " (" << image.cols << " x " << image.rows << ", "
         << bit_depth << " bit)\n";
  io.out << "Preview: " << preview << " (8 bit, black = background, white = brightest pixel)\n";
  PrintSnap(f, live->rig(), image, args.exposure_ms, io.out);
  io.out << LevelLine(f) << "\n";
}

void RunView(const ViewArgs& args, CommandIo io) {
  if (!args.screenshot.empty()) CheckPngOutput(args.screenshot, args.force, "--screenshot");
  RequireDisplay("view");
  if (!args.model.empty()) {
    const CalibrationModel model = LoadModel(args.model);
    MeasureArgs measure;
    measure.model = args.model;
    measure.rig = args.rig;
    measure.at = args.at;
    measure.time_scale = args.time_scale;
    measure.json = true;  // no progress chatter from the rig on stderr
    MeasureSession session(measure, model, io);
    ViewSource source(session.live(), args.exposure_ms, &session, &model);
    ViewLoop(source, session.bit_depth(), args, io.out);
    source.SetWholeSensor(false);
    session.Finish();
    return;
  }
  const std::unique_ptr<LiveCamera> live =
      OpenForSingleExposures(args.rig, args.at, args.exposure_ms, args.time_scale, io.err);
  ViewSource source(*live, args.exposure_ms, nullptr, nullptr);
  ViewLoop(source, live->bit_depth(), args, io.out);
}

}  // namespace irdist
