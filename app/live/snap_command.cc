#include "app/live/snap_command.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <opencv2/core.hpp>
#include <ostream>
#include <sstream>
#include <string>

#include "acquisition/camera.h"
#include "app/display/view_layout.h"
#include "app/live/live_camera.h"
#include "app/live/png_output.h"
#include "app/live/single_exposure.h"
#include "app/processing/frame_features.h"

namespace irdist {
namespace {

// The side of the suggested region of interest: the features' window with room to move.
constexpr int kSuggestedRoiSidePx = 256;

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
// The camera's refusal of the exposure, in snap's terms (its exposure is --exposure-ms).
cv::Mat SnapFrame(const SnapArgs& args, std::ostream& err, std::unique_ptr<LiveCamera>* live) {
  try {
    *live = OpenForSingleExposures(args.rig, args.at, args.exposure_ms, args.time_scale, err);
    return SingleExposure(**live, args.exposure_ms, err).Next();
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
  RequireValid(args, "snap");
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

}  // namespace irdist
