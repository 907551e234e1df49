#include "acquisition/linearity.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "acquisition/camera.h"

namespace irdist {

bool LinearityOptions::IsValid(std::string* why) const {
  auto fail = [why](const char* message) {
    if (why != nullptr) *why = message;
    return false;
  };
  if (!(low_fraction > 0.0 && low_fraction < high_fraction && high_fraction < 1.0)) {
    return fail("linearity fractions must satisfy 0 < low < high < 1");
  }
  if (points < 3 || points > 16) return fail("linearity points must lie in [3, 16]");
  if (window_px < 2) return fail("linearity window_px must be >= 2");
  if (!(limit_percent > 0.0)) return fail("linearity limit_percent must be > 0");
  if (!(saturation_fraction > high_fraction && saturation_fraction <= 1.0)) {
    return fail("linearity saturation_fraction must lie in (high_fraction, 1]");
  }
  return true;
}

std::string LinearityResult::BriefReport() const {
  std::ostringstream out;
  out.precision(3);
  if (!measured) {
    out << "not measured: " << why;
    return out.str();
  }
  out << "linearity error " << error_percent << "% (limit " << limit_percent << "%) over "
      << points_used << " exposures";
  if (points_saturated > 0) out << " (" << points_saturated << " saturated left out)";
  out << ", dark offset " << dark_dn << " DN, line at zero exposure " << intercept_dn << " DN";
  return out.str();
}

LinearityResult FitLinearity(double dark_dn, double full_scale_dn,
                             const std::vector<LinearityPoint>& points,
                             const LinearityOptions& options) {
  LinearityResult r;
  r.dark_dn = dark_dn;
  r.full_scale_dn = full_scale_dn;
  r.limit_percent = options.limit_percent;
  r.points = points;
  const double range = full_scale_dn - dark_dn;
  std::vector<LinearityPoint> used;
  for (const LinearityPoint& p : points) {
    if (p.mean_dn > dark_dn + options.saturation_fraction * range) {
      ++r.points_saturated;
    } else {
      used.push_back(p);
    }
  }
  r.points_used = static_cast<int>(used.size());
  if (!(range > 0.0) || used.size() < 3) {
    r.why = "fewer than 3 unsaturated exposures (" + std::to_string(used.size()) + ")";
    return r;
  }
  double st = 0, sy = 0, stt = 0, sty = 0;
  for (const LinearityPoint& p : used) {
    st += p.exposure_us;
    sy += p.mean_dn;
    stt += p.exposure_us * p.exposure_us;
    sty += p.exposure_us * p.mean_dn;
  }
  const double n = static_cast<double>(used.size());
  const double det = n * stt - st * st;
  if (!(std::fabs(det) > 0.0)) {
    r.why = "the exposures are all the same";
    return r;
  }
  r.slope_dn_per_us = (n * sty - st * sy) / det;
  r.intercept_dn = (sy - r.slope_dn_per_us * st) / n;
  const auto [lo, hi] = std::minmax_element(
      used.begin(), used.end(),
      [](const auto& a, const auto& b) { return a.exposure_us < b.exposure_us; });
  const double span = r.slope_dn_per_us * (hi->exposure_us - lo->exposure_us);
  if (!(span > 0.05 * range)) {
    std::ostringstream why;
    why << "no light: the window rises by " << span << " DN over the series, under 5% of the "
        << range << " DN range (point the camera at the lit source)";
    r.why = why.str();
    return r;
  }
  double worst = 0.0;
  for (const LinearityPoint& p : used) {
    worst = std::max(worst,
                     std::fabs(p.mean_dn - (r.intercept_dn + r.slope_dn_per_us * p.exposure_us)));
  }
  r.error_percent = 100.0 * worst / span;
  r.measured = true;
  return r;
}

namespace {

// The square window (options.window_px) around the frame's brightest spot (box-filtered).
cv::Rect BrightestWindow(const cv::Mat& frame, int window_px) {
  const int side = std::min({window_px, frame.cols, frame.rows});
  cv::Mat smooth;
  cv::blur(frame, smooth, cv::Size(side, side));
  cv::Point peak;
  cv::minMaxLoc(smooth, nullptr, nullptr, nullptr, &peak);
  const int x = std::clamp(peak.x - side / 2, 0, frame.cols - side);
  const int y = std::clamp(peak.y - side / 2, 0, frame.rows - side);
  return {x, y, side, side};
}

double WindowMax(const cv::Mat& frame, const cv::Rect& window) {
  double top = 0.0;
  cv::minMaxLoc(frame(window), nullptr, &top);
  return top;
}

struct Probe {
  cv::Rect window;
  double exposure_us = 0.0;
  double peak_dn = 0.0;  // the window's brightest pixel
  std::string why;       // when no usable probe
};

// Shortened (/4) while the window saturates, lengthened (x4) while it is barely lit.
Probe FindWindow(const GrabAt& grab, double exposure_us, double min_us, double max_us,
                 double dark_dn, double full_scale_dn, const LinearityOptions& options) {
  Probe p;
  p.exposure_us = std::clamp(exposure_us, min_us, max_us);
  const double range = full_scale_dn - dark_dn;
  for (int attempt = 0; attempt < 8; ++attempt) {
    const std::optional<ExposedFrame> frame = grab(p.exposure_us);
    if (!frame || frame->image.empty() || !(frame->exposure_us > 0.0)) {
      p.why = "no frame arrived at " + std::to_string(p.exposure_us) + " us";
      return p;
    }
    p.exposure_us = frame->exposure_us;  // as the camera took it
    p.window = BrightestWindow(frame->image, options.window_px);
    p.peak_dn = WindowMax(frame->image, p.window);
    if (p.peak_dn >= dark_dn + options.saturation_fraction * range) {
      if (p.exposure_us <= min_us) break;
      p.exposure_us = std::max(min_us, p.exposure_us / 4.0);
    } else if (p.peak_dn < dark_dn + 0.2 * range && p.exposure_us < max_us) {
      p.exposure_us = std::min(max_us, p.exposure_us * 4.0);
    } else {
      return p;
    }
  }
  if (p.peak_dn >= dark_dn + options.saturation_fraction * range) {
    p.why = "the window saturates even at the shortest exposure (" + std::to_string(p.exposure_us) +
            " us): dim the source";
  }
  return p;
}

}  // namespace

LinearityResult MeasureLinearity(const GrabAt& grab,
                                 const std::function<std::optional<cv::Mat>()>& grab_dark,
                                 double probe_exposure_us, double min_exposure_us,
                                 double max_exposure_us, double full_scale_dn,
                                 const LinearityOptions& options) {
  LinearityResult failed;
  failed.full_scale_dn = full_scale_dn;
  failed.limit_percent = options.limit_percent;
  const std::optional<cv::Mat> dark = grab_dark();
  if (!dark || dark->empty()) {
    failed.why = "no dark frame arrived";
    return failed;
  }
  const double dark_level = cv::mean(*dark)[0];
  const Probe probe = FindWindow(grab, probe_exposure_us, min_exposure_us, max_exposure_us,
                                 dark_level, full_scale_dn, options);
  if (!probe.why.empty()) {
    failed.why = probe.why;
    return failed;
  }
  const double dark_dn = cv::mean((*dark)(probe.window))[0];
  failed.dark_dn = dark_dn;
  const double range = full_scale_dn - dark_dn;
  const double rise_per_us = (probe.peak_dn - dark_dn) / probe.exposure_us;
  if (!(rise_per_us * max_exposure_us > options.low_fraction * range)) {
    failed.why = "no light: the brightest window stays within " +
                 std::to_string(static_cast<int>(probe.peak_dn - dark_dn)) +
                 " DN of the dark offset even at the longest exposure (point the camera at the "
                 "lit source)";
    return failed;
  }
  std::vector<LinearityPoint> points;
  for (int i = 0; i < options.points; ++i) {
    const double fraction = options.low_fraction + (options.high_fraction - options.low_fraction) *
                                                       i / (options.points - 1);
    const double exposure_us =
        std::clamp(fraction * range / rise_per_us, min_exposure_us, max_exposure_us);
    const std::optional<ExposedFrame> frame = grab(exposure_us);
    if (!frame || frame->image.empty() || !(frame->exposure_us > 0.0)) {
      failed.why = "no frame arrived at " + std::to_string(exposure_us) + " us";
      return failed;
    }
    points.push_back({frame->exposure_us, cv::mean(frame->image(probe.window))[0]});
  }
  return FitLinearity(dark_dn, full_scale_dn, points, options);
}

LinearityResult MeasureCameraLinearity(Camera& camera, const std::function<void()>& fire,
                                       double probe_exposure_us, double min_exposure_us,
                                       double max_exposure_us, int bit_depth,
                                       const LinearityOptions& options) {
  const GrabAt grab = [&camera, &fire](double exposure_us) -> std::optional<ExposedFrame> {
    camera.WriteExposureUs(exposure_us);  // no read-back check: the camera's step is measured
    const double used_us = camera.ExposureUs();
    camera.Flush();
    fire();
    const auto timeout = std::chrono::milliseconds(3000 + static_cast<int>(used_us / 1000));
    const std::optional<RawFrame> frame = camera.WaitFrame(timeout);
    if (!frame || frame->status != FrameStatus::kOk) return std::nullopt;
    return ExposedFrame{frame->image, used_us};
  };
  const bool was_streaming = camera.streaming();
  if (!was_streaming) camera.StartStream();
  const LinearityResult result = MeasureLinearity(
      grab,
      [&grab, min_exposure_us]() -> std::optional<cv::Mat> {
        std::optional<ExposedFrame> dark = grab(min_exposure_us);
        if (!dark) return std::nullopt;
        return dark->image;
      },
      probe_exposure_us,
      min_exposure_us, max_exposure_us, static_cast<double>((1 << bit_depth) - 1), options);
  camera.Flush();
  if (!was_streaming) camera.StopStream();
  camera.SetExposureUs(probe_exposure_us);
  return result;
}

}  // namespace irdist
