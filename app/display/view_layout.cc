#include "app/display/view_layout.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <sstream>

#include <opencv2/imgproc.hpp>

#include "estimator/blur_model.h"
#include "estimator/health.h"

namespace irdist {
namespace {

// 10-90% width of an edge blurred by a Gaussian of unit sd: 2 x 1.2816 (the normal's 90% point).
constexpr double kEdgeWidthPerSigma = 2.0 * 1.2815516;
constexpr std::size_t kFocusFrames = 5;  // the running mean's length

constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
constexpr double kFontScale = 0.5;
constexpr int kLineHeightPx = 20;
constexpr int kMarginPx = 8;
constexpr int kZoomSidePx = 256;
constexpr int kGaugeHeightPx = 22;
constexpr int kMinWindowWidthPx = 640;
constexpr int kMinWindowHeightPx = 480;

int TextWidthPx(const std::string& text) {
  int baseline = 0;
  return cv::getTextSize(text, kFont, kFontScale, 1, &baseline).width;
}

// The frame as 8-bit BGR between `black` and `white` (gray levels), saturated pixels magenta.
cv::Mat Rendered(const cv::Mat& image, int bit_depth, double black, double white) {
  const double span = std::max(1.0, white - black);
  cv::Mat gray, bgr;
  image.convertTo(gray, CV_8U, 255.0 / span, -black * 255.0 / span);
  cv::cvtColor(gray, bgr, cv::COLOR_GRAY2BGR);
  cv::Mat saturated;
  cv::compare(image, FullScale(bit_depth), saturated, cv::CMP_GE);
  bgr.setTo(kSaturatedColour, saturated);
  return bgr;
}

// `bgr` resized by `scale`: whole pixels as blocks when enlarged; when reduced, a block with a
// saturated pixel stays magenta (a single saturated pixel must not vanish in the whole sensor).
cv::Mat Resized(const cv::Mat& bgr, double scale) {
  cv::Mat out;
  if (scale >= 1.0) {
    cv::resize(bgr, out, cv::Size(), scale, scale, cv::INTER_NEAREST);
    return out;
  }
  cv::resize(bgr, out, cv::Size(), scale, scale, cv::INTER_AREA);
  cv::Mat mask, small_mask;
  cv::inRange(bgr, kSaturatedColour, kSaturatedColour, mask);
  cv::resize(mask, small_mask, out.size(), 0, 0, cv::INTER_AREA);
  out.setTo(kSaturatedColour, small_mask > 0);
  return out;
}

cv::Point2f Scaled(double x, double y, double scale) {
  // Pixel centres are at whole coordinates: pixel i covers [i - 0.5, i + 0.5).
  return {static_cast<float>((x + 0.5) * scale - 0.5), static_cast<float>((y + 0.5) * scale - 0.5)};
}

cv::Rect ScaledRect(const cv::Rect& r, double scale) {
  return {static_cast<int>(std::lround(r.x * scale)), static_cast<int>(std::lround(r.y * scale)),
          static_cast<int>(std::lround(r.width * scale)),
          static_cast<int>(std::lround(r.height * scale))};
}

}  // namespace

void DrawFeatures(const Features& f, double scale, cv::Mat* view) {
  cv::rectangle(*view, ScaledRect(f.roi, scale), kWindowColour, 1);
  // The scene pass's findings: the defect pixels replaced, the other blobs masked.
  for (const cv::Point& p : f.scene.defect_px) {  // a box around the pixel, seen at any scale
    cv::rectangle(*view, ScaledRect(cv::Rect(p.x - 1, p.y - 1, 3, 3), scale), kDefectColour, 1);
  }
  for (const cv::Rect& r : f.scene.other_blob_rects) {
    cv::rectangle(*view, ScaledRect(r, scale), kOtherBlobColour, 1);
  }
  const EllipseFit& e = f.ellipse_moments;
  if (!e.valid) return;
  cv::ellipse(*view,
              cv::RotatedRect(Scaled(e.center_px.x, e.center_px.y, scale),
                              cv::Size2f(static_cast<float>(e.major_px * scale),
                                         static_cast<float>(e.minor_px * scale)),
                              static_cast<float>(e.angle_deg)),
              kEllipseColour, 1);
}

namespace {

// The frame scaled to fit `area`, at full scale (the levels as the camera gives them).
cv::Mat FramePanel(const ViewPanel& panel, cv::Size area) {
  const cv::Mat& image = panel.image;
  double scale = std::min(static_cast<double>(area.width) / image.cols,
                          static_cast<double>(area.height) / image.rows);
  if (scale >= 1.0) scale = std::floor(scale);  // whole pixels, crisp
  cv::Mat view = Resized(Rendered(image, panel.bit_depth, 0.0, FullScale(panel.bit_depth)), scale);
  if (panel.roi) cv::rectangle(view, ScaledRect(*panel.roi, scale), kRoiColour, 2);
  if (panel.features != nullptr && panel.features->blob_found) {
    DrawFeatures(*panel.features, scale, &view);
  }
  return view;
}

// The blob enlarged by whole pixels, stretched from the background to the brightest pixel so its
// edge shows; centred on the centroid (the frame's centre without a blob).
cv::Mat ZoomPanel(const ViewPanel& panel, int* factor) {
  const cv::Mat& image = panel.image;
  const Features* f = panel.features;
  const bool blob = f != nullptr && f->blob_found;
  const double major = blob && f->ellipse_moments.valid ? f->ellipse_moments.major_px : 16.0;
  int side = std::clamp(static_cast<int>(std::lround(1.6 * major)) + 6, 12, kZoomSidePx);
  side = std::min({side, image.cols, image.rows});
  const cv::Point2d c = blob ? f->centroid_px : cv::Point2d(image.cols / 2.0, image.rows / 2.0);
  const int x0 = std::clamp(static_cast<int>(std::lround(c.x)) - side / 2, 0, image.cols - side);
  const int y0 = std::clamp(static_cast<int>(std::lround(c.y)) - side / 2, 0, image.rows - side);
  const cv::Mat crop = image(cv::Rect(x0, y0, side, side));
  double low = 0.0, high = 0.0;
  cv::minMaxLoc(crop, &low, &high);
  *factor = std::max(1, kZoomSidePx / side);
  return Resized(Rendered(crop, panel.bit_depth, low, high), *factor);
}

// The focus gauge: with a calibration, -50%..+50% around the calibrated blur (the goal, a green
// tick) with the measured change marked; without, the edge width against twice the best seen.
cv::Mat FocusGauge(const FocusFigure& focus) {
  cv::Mat gauge(kGaugeHeightPx, kZoomSidePx, CV_8UC3, cv::Scalar(40, 40, 40));
  if (!focus.valid) return gauge;
  double position = 0.0;  // 0..1 along the gauge
  bool good = false;
  if (focus.calibrated) {
    cv::line(gauge, {kZoomSidePx / 2, 0}, {kZoomSidePx / 2, kGaugeHeightPx - 1}, kWindowColour, 2);
    position = 0.5 + focus.change;
    good = std::fabs(focus.change) <= HealthOptions().min_sigma_change;
  } else {
    const int best_x = kZoomSidePx / 2;
    cv::line(gauge, {best_x, 0}, {best_x, kGaugeHeightPx - 1}, kWindowColour, 2);
    position = 0.5 * focus.edge_width_px / std::max(focus.best_edge_width_px, 1e-9);
    good = focus.edge_width_px <= 1.05 * focus.best_edge_width_px;
  }
  const int x = std::clamp(static_cast<int>(std::lround(position * (kZoomSidePx - 1))), 0,
                           kZoomSidePx - 1);
  cv::rectangle(gauge, cv::Rect(std::max(0, x - 2), 2, 5, kGaugeHeightPx - 4),
                good ? cv::Scalar(0, 255, 255) : kEllipseColour, cv::FILLED);
  return gauge;
}

void Paste(const cv::Mat& part, int x, int y, cv::Mat* canvas) {
  const cv::Rect where(x, y, std::min(part.cols, canvas->cols - x),
                       std::min(part.rows, canvas->rows - y));
  if (where.width <= 0 || where.height <= 0) return;
  part(cv::Rect(0, 0, where.width, where.height)).copyTo((*canvas)(where));
}

void PutText(const std::string& text, int x, int y, cv::Mat* canvas) {
  cv::putText(*canvas, text, cv::Point(x, y), kFont, kFontScale, kTextColour, 1, cv::LINE_AA);
}

// The gauge's scale under it: its ends and its centre (the goal, the green tick).
void GaugeLabels(bool calibrated, int x, int y, cv::Mat* canvas) {
  const std::string left = calibrated ? "-50%" : "0";
  const std::string centre = calibrated ? "calibrated" : "best";
  const std::string right = calibrated ? "+50%" : "2x best";
  PutText(left, x, y, canvas);
  PutText(centre, x + (kZoomSidePx - TextWidthPx(centre)) / 2, y, canvas);
  PutText(right, x + kZoomSidePx - TextWidthPx(right), y, canvas);
}

}  // namespace

std::vector<std::string> WrapText(const std::string& text, int width_px) {
  std::vector<std::string> lines;
  std::istringstream words(text);
  std::string word, line;
  while (words >> word) {
    const std::string joined = line.empty() ? word : line + " " + word;
    if (TextWidthPx(joined) <= width_px) {
      line = joined;
      continue;
    }
    if (!line.empty()) lines.push_back(line);
    line = word;
    while (line.size() > 1 && TextWidthPx(line) > width_px) {  // a word wider than the window
      std::size_t fits = line.size() - 1;
      while (fits > 1 && TextWidthPx(line.substr(0, fits)) > width_px) --fits;
      lines.push_back(line.substr(0, fits));
      line = line.substr(fits);
    }
  }
  if (!line.empty()) lines.push_back(line);
  return lines;
}

std::string FocusFigure::Line() const {
  char text[256];
  if (!valid) {
    return "focus: no figure for this frame (no usable blob: none found, saturated or on the "
           "border)";
  }
  if (calibrated) {
    const bool as_calibrated = std::fabs(change) <= HealthOptions().min_sigma_change;
    const double percent = std::round(100.0 * change) + 0.0;  // + 0.0: no "-0%"
    std::snprintf(text, sizeof(text),
                  "focus: blur %.2f px, calibrated %.2f px at %.0f mm: %+.0f%% (%s)", blur_sigma_px,
                  calibrated_sigma_px, at_d_mm, percent,
                  as_calibrated ? "as calibrated" : "turn the focus ring to bring it to 0%");
  } else {
    std::snprintf(text, sizeof(text),
                  "focus: edge width (10-90%%) %.2f px, best so far %.2f px: turn the focus ring "
                  "to make it smallest",
                  edge_width_px, best_edge_width_px);
  }
  return text;
}

FocusFigure FocusTracker::Add(const Features& f, double d_mm) {
  FocusFigure figure;  // none for a frame without a usable blob: no stale figure shown
  if (!f.Usable() || !std::isfinite(f.blur_var_px2) || !(f.blur_var_px2 > 0.0)) return figure;
  recent_var_px2_.push_back(f.blur_var_px2);
  if (recent_var_px2_.size() > kFocusFrames) recent_var_px2_.erase(recent_var_px2_.begin());
  const double var = std::accumulate(recent_var_px2_.begin(), recent_var_px2_.end(), 0.0) /
                     static_cast<double>(recent_var_px2_.size());
  figure.valid = true;
  figure.blur_sigma_px = std::sqrt(std::max(var - kPixelAreaVarPx2, 0.0));
  figure.edge_width_px = kEdgeWidthPerSigma * std::sqrt(var);
  if (best_edge_width_px_ <= 0.0 || figure.edge_width_px < best_edge_width_px_) {
    best_edge_width_px_ = figure.edge_width_px;
  }
  figure.best_edge_width_px = best_edge_width_px_;
  if (calibration_ != nullptr && calibration_->fitted() && d_mm > 0.0) {
    figure.calibrated = true;
    figure.at_d_mm = d_mm;
    const double calibrated_var_px2 = calibration_->BlurVarPx2(d_mm);
    figure.calibrated_sigma_px = std::sqrt(std::max(calibrated_var_px2 - kPixelAreaVarPx2, 1e-6));
    figure.change = BlurSigmaChange(var, calibrated_var_px2);  // the health check's figure
  }
  return figure;
}

cv::Mat ComposeView(const ViewPanel& panel, cv::Size window_size) {
  const int width = std::max(window_size.width, kMinWindowWidthPx);
  const int height = std::max(window_size.height, kMinWindowHeightPx);
  std::vector<std::string> lines;
  for (const std::string& line : panel.lines) {
    for (std::string& wrapped : WrapText(line, width - 2 * kMarginPx)) lines.push_back(wrapped);
  }
  const int text_height = static_cast<int>(lines.size()) * kLineHeightPx + kMarginPx;
  const int side_width = kZoomSidePx + 2 * kMarginPx;
  const cv::Size area(width - side_width, std::max(kMinWindowHeightPx / 2, height - text_height));
  const cv::Mat frame = FramePanel(panel, area);
  int factor = 1;
  const cv::Mat zoom = ZoomPanel(panel, &factor);
  const int gauge_y = kLineHeightPx + zoom.rows + kMarginPx;
  const int side_height = gauge_y + kGaugeHeightPx + kLineHeightPx;
  cv::Mat canvas(std::max(frame.rows, side_height) + text_height, width, CV_8UC3,
                 cv::Scalar(0, 0, 0));
  Paste(frame, 0, 0, &canvas);
  const int side_x = frame.cols + kMarginPx;
  PutText("zoom x" + std::to_string(factor) + " on the blob", side_x, kLineHeightPx - 6, &canvas);
  Paste(zoom, side_x, kLineHeightPx, &canvas);
  Paste(FocusGauge(panel.focus), side_x, gauge_y, &canvas);
  GaugeLabels(panel.focus.calibrated, side_x, gauge_y + kGaugeHeightPx + kLineHeightPx - 4,
              &canvas);
  const int text_top = std::max(frame.rows, side_height);
  for (std::size_t i = 0; i < lines.size(); ++i) {
    PutText(lines[i], kMarginPx, text_top + static_cast<int>(i + 1) * kLineHeightPx - 4, &canvas);
  }
  return canvas;
}

}  // namespace irdist
