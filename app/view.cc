#include "app/view.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <memory>
#include <opencv2/highgui.hpp>
#include <opencv2/imgcodecs.hpp>
#include <ostream>
#include <sstream>

#include "acquisition/bracket.h"
#include "app/live_camera.h"
#include "app/measure.h"
#include "app/offline.h"
#include "app/show.h"
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

// One exposure after another on the rig's camera (snap, view without a model).
class SingleExposure {
 public:
  SingleExposure(const std::string& rig, const std::vector<double>& at, double exposure_ms,
                 double time_scale, std::ostream& err) {
    LiveCameraOptions options;
    options.rig_spec = rig;
    options.at = at;
    options.time_scale = time_scale;
    options.first_exposure_us = exposure_ms * 1000.0;
    options.longest_exposure_us = exposure_ms * 1000.0;
    live_ = std::make_unique<LiveCamera>(options, err);
    BracketOptions bracket;
    // BracketCapture takes a reference and at least one measurement: two frames at the same
    // exposure, the second one shown (it also skips a first frame after an idle stream).
    bracket.exposures_us = {exposure_ms * 1000.0, exposure_ms * 1000.0};
    bracket.trigger_source = live_->trigger_source();
    bracket.frame_timeout = std::chrono::milliseconds(live_->frame_timeout_ms());
    capture_ = std::make_unique<BracketCapture>(live_->camera(), bracket);
  }
  cv::Mat Next() {
    BracketResult result = capture_->Capture(live_->Trigger());
    if (!result.complete) result = capture_->Capture(live_->Trigger());
    if (!result.complete) throw CameraError("no frame twice: " + result.failure);
    return result.frames.back().image;
  }
  LiveCamera& live() { return *live_; }

 private:
  std::unique_ptr<LiveCamera> live_;
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
  const double max_percent = 100.0 * max_level / (std::ldexp(1.0, bit_depth) - 1.0);
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
  const double full_scale = std::ldexp(1.0, bit_depth) - 1.0;
  const double black = std::clamp(f.background * full_scale, min_level, max_level);
  const double span = std::max(1.0, max_level - black);
  cv::Mat preview;
  image.convertTo(preview, CV_8U, 255.0 / span, -black * 255.0 / span);
  return preview;
}

// What the window shows of one frame.
struct ViewFrame {
  cv::Mat image;
  Features features;
  std::vector<std::string> lines;
};

constexpr const char* kKeysLine = "keys: q or Esc quit, s save a screenshot (view-N.png)";

// Shows frames from `next` until q/Esc, or `frames` frames; saves the last view to `screenshot`.
void ViewLoop(const std::function<ViewFrame()>& next, int bit_depth, const ViewArgs& args,
              std::ostream& out) {
  const std::string window = "irdist view";
  OpenWindow(window, "view");
  cv::Mat shown;
  int saved = 0;
  for (int n = 0; args.frames <= 0 || n < args.frames; ++n) {
    ViewFrame frame = next();
    frame.lines.push_back(kKeysLine);
    shown = FrameOverlay(frame.image, bit_depth, &frame.features, frame.lines);
    cv::imshow(window, shown);
    const int key = cv::waitKey(1);
    if (key == 'q' || key == 27) break;
    if (key == 's') {
      std::string file;  // the next view-N.png that does not exist: none is replaced
      std::error_code ec;
      do {
        file = "view-" + std::to_string(saved++) + ".png";
      } while (fs::exists(fs::symlink_status(file, ec)));
      WritePng(file, shown, "screenshot");
      out << "Saved " << file << "\n";
    }
  }
  if (!args.screenshot.empty() && !shown.empty()) WritePng(args.screenshot, shown, "screenshot");
  cv::destroyWindow(window);
}

}  // namespace

namespace {

// The camera's refusal of the exposure, in snap's terms (its exposure is --exposure-ms).
cv::Mat SnapFrame(const SnapArgs& args, std::ostream& err, std::unique_ptr<SingleExposure>* cam) {
  try {
    *cam = std::make_unique<SingleExposure>(args.rig, args.at, args.exposure_ms,
                                            args.time_scale, err);
    return (*cam)->Next();
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
  std::unique_ptr<SingleExposure> camera;
  const cv::Mat image = SnapFrame(args, io.err, &camera);
  WritePng(args.out, image, "frame");
  const int bit_depth = camera->live().bit_depth();
  const Features f = FrameFeatures(image, bit_depth, FeatureOptions{});
  WritePng(preview, PreviewImage(image, f, bit_depth), "preview");
  io.out << "Frame: " << args.out << " (" << image.cols << " x " << image.rows << ", "
         << bit_depth << " bit)\n";
  io.out << "Preview: " << preview << " (8 bit, black = background, white = brightest pixel)\n";
  PrintSnap(f, camera->live().rig(), image, args.exposure_ms, io.out);
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
    const auto t0 = std::chrono::steady_clock::now();
    ViewLoop(
        [&] {
          const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
          const MeasureSample s = session.Next(t);
          return ViewFrame{session.last_image(), session.last_features(),
                           {MeasureLine(s), LevelLine(session.last_features())}};
        },
        session.bit_depth(), args, io.out);
    session.Finish();
    return;
  }
  SingleExposure camera(args.rig, args.at, args.exposure_ms, args.time_scale, io.err);
  const int bit_depth = camera.live().bit_depth();
  ViewLoop(
      [&] {
        ViewFrame frame;
        frame.image = camera.Next();
        frame.features = FrameFeatures(frame.image, bit_depth, FeatureOptions{});
        char exposure[64];
        std::snprintf(exposure, sizeof(exposure), "exposure %.3g ms", args.exposure_ms);
        frame.lines = {exposure,
                       LevelLine(frame.features)};
        return frame;
      },
      bit_depth, args, io.out);
}

}  // namespace irdist
