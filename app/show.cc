// playback --show: an OpenCV window over the recording's frames.
#include <algorithm>
#include <cstdlib>
#include <map>
#include <opencv2/highgui.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "acquisition/recording.h"
#include "app/show.h"

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
    cv::namedWindow(window, cv::WINDOW_NORMAL);
  } catch (const cv::Exception& e) {
    throw DisplayError(what + ": cannot open a window: " + e.what());
  }
}

namespace {

// A small frame (a region of interest) is enlarged to this width for display, by whole pixels.
constexpr int kMinDisplayWidthPx = 768;

cv::Point2f Scaled(double x, double y, int scale) {
  // Pixel centres are at whole coordinates: pixel i covers [i - 0.5, i + 0.5).
  return {static_cast<float>((x + 0.5) * scale - 0.5), static_cast<float>((y + 0.5) * scale - 0.5)};
}

void DrawFeatures(const Features& f, int scale, cv::Mat* view) {
  const cv::Rect r = f.roi;
  cv::rectangle(*view, cv::Rect(r.x * scale, r.y * scale, r.width * scale, r.height * scale),
                cv::Scalar(0, 255, 0), 1);
  const EllipseFit& e = f.ellipse_moments;
  if (!e.valid) return;
  cv::ellipse(*view,
              cv::RotatedRect(Scaled(e.center_px.x, e.center_px.y, scale),
                              cv::Size2f(static_cast<float>(e.major_px * scale),
                                         static_cast<float>(e.minor_px * scale)),
                              static_cast<float>(e.angle_deg)),
              cv::Scalar(0, 0, 255), 1);
}

}  // namespace

cv::Mat FrameOverlay(const cv::Mat& image, int bit_depth, const Features* features,
                     const std::vector<std::string>& lines) {
  const double full_scale = (1 << bit_depth) - 1;
  cv::Mat gray;
  image.convertTo(gray, CV_8U, 255.0 / full_scale);
  const int scale = std::max(1, kMinDisplayWidthPx / std::max(1, image.cols));
  if (scale > 1) cv::resize(gray, gray, cv::Size(), scale, scale, cv::INTER_NEAREST);
  cv::Mat view;
  cv::cvtColor(gray, view, cv::COLOR_GRAY2BGR);
  if (features != nullptr) DrawFeatures(*features, scale, &view);
  for (size_t i = 0; i < lines.size(); ++i) {
    cv::putText(view, lines[i], cv::Point(8, 22 + static_cast<int>(i) * 24),
                cv::FONT_HERSHEY_SIMPLEX, 0.55, cv::Scalar(0, 255, 255), 1);
  }
  return view;
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
    cv::imshow(window, FrameOverlay(reader.LoadImage(row), reader.header().bit_depth,
                                    f != features.end() ? &f->second : nullptr,
                                    {text.str(), "any key: next frame, q or Esc: quit"}));
    const int key = cv::waitKey(0);
    if (key == 'q' || key == 27) break;
  }
  cv::destroyWindow(window);
}

}  // namespace irdist
