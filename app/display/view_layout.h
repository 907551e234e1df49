#pragma once
// What `irdist view` draws (app/live/view.cc shows it): one window image laid out to the window's
// size, so nothing runs off its edge. The frame (the ROI, or the whole sensor with the ROI drawn)
// with saturated pixels in magenta, the features' window and ellipse; a zoom on the blob; the
// focus figure as a gauge; the text below, wrapped to the window's width. Pure drawing: no
// camera, no window (tests/app/display/view_layout_test.cc checks it on synthetic frames).

#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "estimator/features.h"

namespace irdist {

struct BlurCalibration;  // estimator/blur_model.h

// The focus figure of the frames seen so far, for a user turning the lens. With a model: the blob's
// blur sigma (px, the pixel's own area removed) against the calibrated blur at the estimated
// distance; the goal is 0% change. Without one: the edge's 10-90% width (px, as the pixels see it),
// smaller is sharper, the smallest seen so far beside it.
struct FocusFigure {
  bool valid = false;              // a usable blob with a measured blur
  bool calibrated = false;         // compared with a model's calibrated blur
  double blur_sigma_px = 0.0;      // measured (mean of the last few frames)
  double calibrated_sigma_px = 0.0;
  double at_d_mm = 0.0;            // the distance the calibrated blur is taken at
  double change = 0.0;             // blur_sigma / calibrated_sigma - 1
  double edge_width_px = 0.0;      // 10-90% edge width of the measured blur
  double best_edge_width_px = 0.0; // the smallest seen so far
  std::string Line() const;        // the text line ("focus: ...")
};

// Follows the focus over frames: a running mean of the last few frames' blur (one frame's
// measurement is noisy), and the best edge width seen.
class FocusTracker {
 public:
  // `calibration` (may be null: no model) must outlive the tracker.
  explicit FocusTracker(const BlurCalibration* calibration) : calibration_(calibration) {}
  // Adds a frame's features; `d_mm` is the estimated distance (<= 0: none, no comparison). A
  // frame without a usable blob gives no figure (valid = false) and leaves the history as it is.
  FocusFigure Add(const Features& f, double d_mm);

 private:
  const BlurCalibration* calibration_;
  std::vector<double> recent_var_px2_;
  double best_edge_width_px_ = 0.0;
};

// One window image's content.
struct ViewPanel {
  cv::Mat image;                 // CV_16UC1, the frame as taken (ROI or whole sensor)
  int bit_depth = 12;
  const Features* features = nullptr;  // of `image` (null: none drawn)
  std::optional<cv::Rect> roi;   // the rig's ROI in `image`'s pixels, drawn (whole-sensor view)
  FocusFigure focus;
  std::vector<std::string> lines;  // text, wrapped to the window's width
};

// Colours (BGR) of the drawing, named for the tests and docs/view.md.
inline const cv::Scalar kSaturatedColour(255, 0, 255);  // magenta
inline const cv::Scalar kRoiColour(255, 255, 0);        // cyan
inline const cv::Scalar kWindowColour(0, 255, 0);       // green: the features' window
inline const cv::Scalar kEllipseColour(0, 0, 255);      // red: the moments' ellipse
inline const cv::Scalar kTextColour(255, 255, 255);
inline const cv::Scalar kDefectColour(0, 255, 255);    // yellow: a defect pixel replaced
inline const cv::Scalar kOtherBlobColour(0, 128, 255);  // orange: another blob masked

// The largest gray level of `bit_depth` bits (saturation).
inline double FullScale(int bit_depth) { return std::ldexp(1.0, bit_depth) - 1.0; }

// The window image for `panel`, `window_size` wide and at most as high (text included); a window
// size below 640 x 480 is taken as 640 x 480.
cv::Mat ComposeView(const ViewPanel& panel, cv::Size window_size);

// The features' window (green), the moments' ellipse (red), the defect pixels replaced (yellow)
// and the other blobs masked (orange) on `view`, a frame enlarged or
// reduced by `scale` (pixel i covers [i - 0.5, i + 0.5) before scaling).
void DrawFeatures(const Features& f, double scale, cv::Mat* view);

// `text` cut at spaces into lines no wider than `width_px` in the view's font (a word longer than
// the width is cut inside).
std::vector<std::string> WrapText(const std::string& text, int width_px);

}  // namespace irdist
