// playback --show: an OpenCV window over the recording's frames.
#include <cstdlib>
#include <map>
#include <opencv2/highgui.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "acquisition/recording.h"
#include "app/show.h"

namespace irdist {

void ShowPlayback(const RecordingReader& reader,
                  const std::map<std::int64_t, Features>& features,
                  const std::vector<EstimateRow>& estimates) {
  const char* display =
      std::getenv("DISPLAY");  // NOLINT(concurrency-mt-unsafe): read once, nobody sets it
  const char* wayland = std::getenv("WAYLAND_DISPLAY");  // NOLINT(concurrency-mt-unsafe)
  if ((display == nullptr || *display == '\0') && (wayland == nullptr || *wayland == '\0')) {
    throw DisplayError(
        "--show needs a display (DISPLAY or WAYLAND_DISPLAY is not set); run it "
        "in a desktop session or with X forwarding (ssh -X), or leave --show out.");
  }
  std::map<int, const EstimateRow*> joint;
  for (const EstimateRow& row : estimates) {
    if (row.method == "i0_free" && row.dt_ms == 0.0) joint[row.bracket] = &row;
  }
  const std::string window = "irdist playback";
  try {
    cv::namedWindow(window, cv::WINDOW_NORMAL);
  } catch (const cv::Exception& e) {
    throw DisplayError(std::string("--show: cannot open a window: ") + e.what());
  }
  const double full_scale = (1 << reader.header().bit_depth) - 1;
  for (const FrameRecord& row : reader.rows()) {
    cv::Mat gray;
    reader.LoadImage(row).convertTo(gray, CV_8U, 255.0 / full_scale);
    cv::Mat view;
    cv::cvtColor(gray, view, cv::COLOR_GRAY2BGR);
    const auto f = features.find(row.index);
    if (f != features.end()) {
      cv::rectangle(view, f->second.roi, cv::Scalar(0, 255, 0), 1);
      const EllipseFit& e = f->second.ellipse_moments;
      if (e.valid) {
        cv::ellipse(
            view,
            cv::RotatedRect(
                cv::Point2f(static_cast<float>(e.center_px.x), static_cast<float>(e.center_px.y)),
                cv::Size2f(static_cast<float>(e.major_px), static_cast<float>(e.minor_px)),
                static_cast<float>(e.angle_deg)),
            cv::Scalar(0, 0, 255), 1);
      }
    }
    std::ostringstream text;
    text << row.file << " bracket " << row.bracket_id << " " << FrameRoleName(row.role) << " "
         << row.requested_exposure_us / 1000.0 << " ms, true d " << row.slide_mm << " mm";
    const auto est = joint.find(static_cast<int>(row.bracket_id));
    if (est != joint.end() && est->second->ok) {
      text << ", estimate " << est->second->d_mm << " mm, theta " << est->second->theta_deg;
    }
    cv::putText(view, text.str(), cv::Point(10, 30), cv::FONT_HERSHEY_SIMPLEX, 0.7,
                cv::Scalar(0, 255, 255), 2);
    cv::imshow(window, view);
    const int key = cv::waitKey(0);
    if (key == 'q' || key == 27) break;
  }
  cv::destroyWindow(window);
}

}  // namespace irdist
