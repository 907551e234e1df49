#include "sim/renderer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace irdist::sim {
namespace {

bool SameGeometry(const PoseState& a, const PoseState& b) {
  return a.slide_mm == b.slide_mm && a.pan_deg == b.pan_deg && a.tilt_deg == b.tilt_deg;
}

// Adds `weight * w` into `acc`, growing acc's rectangle to the union.
void Accumulate(SignalWindow& acc, const SignalWindow& w, double weight) {
  if (w.rect.empty()) return;
  if (acc.rect.empty()) {
    acc.rect = w.rect;
    acc.electrons = w.electrons * weight;
    return;
  }
  const cv::Rect u = acc.rect | w.rect;
  if (u != acc.rect) {
    cv::Mat1f grown = cv::Mat1f::zeros(u.height, u.width);
    acc.electrons.copyTo(grown(acc.rect - u.tl()));
    acc.electrons = grown;
    acc.rect = u;
  }
  cv::Mat1f view = acc.electrons(w.rect - u.tl());
  cv::scaleAdd(w.electrons, weight, view, view);
}

}  // namespace

std::string GroundTruth::BriefReport() const {
  char text[320];
  std::snprintf(text, sizeof(text),
                "theta %.1f deg, ellipse %.2f x %.2f px, blob 2-sigma %.2f x %.2f px, I0 %.1f "
                "mW/sr, signal %.0f e-, peak %.0f e- = %.0f ADC = %.0f gray%s",
                theta_deg, major_px, minor_px, width_px, height_px, intensity_mw_sr, signal_e,
                peak_signal_e, peak_adc, peak_gray, saturated ? " (SATURATED)" : "");
  return text;
}

FrameConditions StaticConditions(double slide_mm, double pan_deg, double tilt_deg, double bias_ma,
                                 double exposure_s) {
  FrameConditions c;
  c.pose_start.slide_mm = slide_mm;
  c.pose_start.pan_deg = pan_deg;
  c.pose_start.tilt_deg = tilt_deg;
  c.pose_start.bias_ma = bias_ma;
  c.pose_end = c.pose_start;
  c.exposure_s = exposure_s;
  return c;
}

// The defects near the blob lie around the emitter's image centre at the default pose (on the
// optical axis: the sensor's centre, whatever the slide).
Renderer::Renderer(const RigPhysics& physics)
    : scene_(physics),
      lab_(scene_),
      sensor_(physics.sensor, scene_.Project(PoseState{}).center_x_px,
              scene_.Project(PoseState{}).center_y_px),
      ambient_margin_px_(static_cast<int>(
          CrosstalkKernel(physics.sensor.crosstalk_sigma_px, physics.sensor.crosstalk_shape)
              .size())) {}

SignalWindow Renderer::EmitterSignal(const PoseState& pose, double intensity_mw_sr,
                                     double exposure_s) const {
  SignalWindow signal = scene_.RenderSignal(pose, intensity_mw_sr, exposure_s);
  if (const auto mirror = lab_.ReflectionDisc(pose, intensity_mw_sr)) {
    Accumulate(signal, scene_.RenderDisc(*mirror, exposure_s), 1.0);
  }
  return signal;
}

SignalWindow Renderer::Signal(const FrameConditions& c) const {
  const double i_start = scene_.OnAxisIntensityMwSr(c.pose_start.bias_ma, c.junction_rise_k);
  const double i_end = scene_.OnAxisIntensityMwSr(c.pose_end.bias_ma, c.junction_rise_k);
  SignalWindow acc;
  const double sub_steps = static_cast<double>(c.sub_steps.size());
  for (const PoseState& pose : c.sub_steps) {  // a moving exposure, in equal parts
    const double intensity = scene_.OnAxisIntensityMwSr(pose.bias_ma, c.junction_rise_k);
    Accumulate(acc, EmitterSignal(pose, intensity, c.exposure_s / sub_steps), 1.0);
  }
  if (c.sub_steps.empty() && SameGeometry(c.pose_start, c.pose_end)) {
    acc = EmitterSignal(c.pose_start, 0.5 * (i_start + i_end), c.exposure_s);
  } else if (c.sub_steps.empty()) {
    // Moving during the exposure: half of it at each end (a two-point smear).
    Accumulate(acc, EmitterSignal(c.pose_start, i_start, 0.5 * c.exposure_s), 1.0);
    Accumulate(acc, EmitterSignal(c.pose_end, i_end, 0.5 * c.exposure_s), 1.0);
  }
  if (const auto second = lab_.SecondSourceDisc()) {
    Accumulate(acc, scene_.RenderDisc(*second, c.exposure_s), 1.0);
  }
  return acc;
}

void Renderer::Render(const FrameConditions& c, std::uint64_t frame_index, PixelFormat format,
                      cv::Point roi_origin, cv::Mat& out) const {
  SignalWindow signal = Signal(c);
  if (lab_.AmbientOn()) {  // over the region and the reach of the crosstalk around it
    const SensorOptions& s = sensor_.options();
    const cv::Rect around =
        cv::Rect(roi_origin.x - ambient_margin_px_, roi_origin.y - ambient_margin_px_,
                 out.cols + 2 * ambient_margin_px_, out.rows + 2 * ambient_margin_px_) &
        cv::Rect(0, 0, s.width_px, s.height_px);
    Accumulate(signal, lab_.Ambient(around, c.exposure_s), 1.0);
  }
  sensor_.Expose(signal, c.exposure_s, frame_index, format, roi_origin, out, c.black_offset_dn);
}

cv::Mat Renderer::Render(const FrameConditions& c, std::uint64_t frame_index,
                         PixelFormat format) const {
  const SensorOptions& s = sensor_.options();
  cv::Mat out(s.height_px, s.width_px, FormatCvType(format));
  Render(c, frame_index, format, cv::Point(0, 0), out);
  return out;
}

GroundTruth Renderer::Describe(const PoseState& pose, double exposure_s, PixelFormat format,
                               double junction_rise_k) const {
  GroundTruth truth;
  const EmitterImage image = scene_.Project(pose);
  truth.theta_deg = image.theta_deg;
  truth.major_px = image.major_px;
  truth.minor_px = image.minor_px;
  truth.blur_sigma_px = scene_.BlurSigmaPx(pose.slide_mm);
  truth.coc_px = scene_.CircleOfConfusionPx(pose.slide_mm);
  truth.intensity_mw_sr = scene_.OnAxisIntensityMwSr(pose.bias_ma, junction_rise_k);
  // Shape and peak at a unit intensity (the shape does not depend on it), then scaled; the
  // charge as the pixels collect it (crosstalk included).
  const SignalWindow w =
      DiffuseCharge(scene_.RenderSignal(pose, 1.0, exposure_s), sensor_.options());
  double sum = 0, sx = 0, sy = 0, sxx = 0, syy = 0, peak = 0;
  for (int r = 0; r < w.electrons.rows; ++r) {
    for (int col = 0; col < w.electrons.cols; ++col) {
      const double v = w.electrons(r, col);
      sum += v;
      sx += v * col;
      sy += v * r;
      sxx += v * col * col;
      syy += v * r * r;
      peak = std::max(peak, v);
    }
  }
  if (sum > 0) {
    const double mx = sx / sum, my = sy / sum;
    truth.width_px = 2.0 * std::sqrt(std::max(0.0, sxx / sum - mx * mx));
    truth.height_px = 2.0 * std::sqrt(std::max(0.0, syy / sum - my * my));
  }
  truth.signal_e = sum * truth.intensity_mw_sr;
  truth.peak_signal_e = peak * truth.intensity_mw_sr;
  truth.peak_adc = sensor_.MeanAdc(truth.peak_signal_e, exposure_s);
  const SensorOptions& s = sensor_.options();
  const double dark_e = (s.dark_current_e_per_s + s.background_e_per_s) * exposure_s;
  truth.saturated = truth.peak_signal_e + dark_e >= s.full_well_e || truth.peak_adc >= s.AdcMax();
  truth.peak_gray = truth.peak_adc * std::pow(2.0, FormatBits(format) - s.adc_bits);
  return truth;
}

}  // namespace irdist::sim
