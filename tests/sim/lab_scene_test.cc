#include "sim/lab_scene.h"

#include <cmath>
#include <cstdint>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "base/pi.h"
#include "sim/renderer.h"

namespace irdist::sim {
namespace {

constexpr double kDeg = kPi / 180.0;

PoseState Pose(double slide_mm, double pan_deg, double tilt_deg, double bias_ma = 300.0) {
  PoseState p;
  p.slide_mm = slide_mm;
  p.pan_deg = pan_deg;
  p.tilt_deg = tilt_deg;
  p.bias_ma = bias_ma;
  return p;
}

double Sum(const SignalWindow& w) { return cv::sum(w.electrons)[0]; }

// The intensity-weighted centre of a window, full-sensor pixels (pixel centres at + 0.5).
cv::Point2d Centroid(const SignalWindow& w) {
  double s = 0, sx = 0, sy = 0;
  for (int r = 0; r < w.electrons.rows; ++r) {
    for (int c = 0; c < w.electrons.cols; ++c) {
      const double v = w.electrons(r, c);
      s += v;
      sx += v * (w.rect.x + c + 0.5);
      sy += v * (w.rect.y + r + 0.5);
    }
  }
  return {sx / s, sy / s};
}

double PixelsPerMm(const RigPhysics& p) {
  return p.optics.focal_length_mm / (p.sensor.pixel_pitch_um * 1e-3);
}

std::uint64_t HashFrame(const cv::Mat& frame) {
  std::uint64_t h = 1469598103934665603ull;  // FNV-1a
  for (int r = 0; r < frame.rows; ++r) {
    const auto* p = frame.ptr<std::uint8_t>(r);
    for (size_t i = 0; i < frame.cols * frame.elemSize(); ++i) {
      h ^= p[i];
      h *= 1099511628211ull;
    }
  }
  return h;
}

// Four frames: the default rig on the axis (full sensor, Mono12); tilted, Mono8, in the ROI;
// moving during the exposure, Mono16; an off-axis emitter with fixed-pattern noise, crosstalk and
// no defocus at 3 m.
std::vector<std::uint64_t> FrameHashes(const RigPhysics& base) {
  std::vector<std::uint64_t> hashes;
  const cv::Point roi(512, 384);
  {
    const Renderer r(base);
    hashes.push_back(HashFrame(
        r.Render(StaticConditions(2000, 0, 0, 300, 0.030), 3, PixelFormat::kMono12)));
    cv::Mat out(256, 256, CV_8UC1);
    r.Render(StaticConditions(1500, 30, 10, 450, 0.008), 4, PixelFormat::kMono8, roi, out);
    hashes.push_back(HashFrame(out));
    FrameConditions moving = StaticConditions(2000, 0, 0, 300, 0.020);
    moving.pose_end.slide_mm = 2010;
    moving.pose_end.pan_deg = 5;
    moving.junction_rise_k = 3.0;
    cv::Mat out16(256, 256, CV_16UC1);
    r.Render(moving, 5, PixelFormat::kMono16, roi, out16);
    hashes.push_back(HashFrame(out16));
  }
  RigPhysics p = base;
  p.emitter.offset_x_mm = 40;
  p.emitter.offset_y_mm = -20;
  p.sensor.prnu_percent = 1.0;
  p.sensor.dsnu_e = 3.0;
  p.sensor.crosstalk_sigma_px = 0.6;
  p.optics.focus_mm = 0.0;
  const Renderer r(p);
  cv::Mat out(256, 256, CV_16UC1);
  r.Render(StaticConditions(3000, -20, 15, 500, 0.035), 6, PixelFormat::kMono12, roi, out);
  hashes.push_back(HashFrame(out));
  return hashes;
}

// With every lab fault off (the defaults, and each fault's "off" value written out), the frames
// are byte for byte those of the renderer before the lab's scene existed (commit bca3a82, where
// these hashes were taken with the same FrameHashes; libstdc++'s random distributions).
TEST(LabScene, AllOffGivesTheFramesOfBefore) {
  const std::vector<std::uint64_t> before = {0x802451bb49cd4660ull, 0xda6dfc2b361f5119ull,
                                             0x7b2ea3929c316655ull, 0xb86b95b2d5ebeb2full};
  EXPECT_EQ(FrameHashes(RigPhysics{}), before);
  RigPhysics off;
  off.scene.reflection.plane_below_mm = 8.0;  // reflectance 0
  off.scene.second_source.position_mm = {30, 0, 2000};  // intensity 0
  off.scene.occluder.edge_angle_deg = 30;  // covered_fraction 0
  off.scene.ambient.gradient_x_percent = 50;  // centre rate 0
  off.sensor.defects.defects_near_blob = 0;
  EXPECT_EQ(FrameHashes(off), before);
}

// The reflection's image lies 2 h f / (d pitch) below the IRED's (the mirror geometry), within
// 0.5 px, on the axis and tilted.
TEST(LabScene, ReflectionLiesAtTheMirrorImagesOffset) {
  RigPhysics p;
  p.scene.reflection = {8.3, 0.2};
  const Scene scene(p);
  const LabScene lab(scene);
  for (const PoseState& pose : {Pose(1500, 0, 0), Pose(2000, 20, 0), Pose(3000, 0, 15)}) {
    const double i0 = scene.OnAxisIntensityMwSr(pose.bias_ma, 0.0);
    const cv::Point2d ired = Centroid(scene.RenderSignal(pose, i0, 0.01));
    const auto mirror = lab.ReflectionDisc(pose, i0);
    ASSERT_TRUE(mirror.has_value());
    const cv::Point2d image = Centroid(scene.RenderDisc(*mirror, 0.01));
    const double expected_px = 2.0 * 8.3 * PixelsPerMm(p) / pose.slide_mm;
    EXPECT_NEAR(image.y - ired.y, expected_px, 0.5) << pose.slide_mm;
    EXPECT_NEAR(image.x - ired.x, 0.0, 0.1);
  }
}

// Its flux is the reflectance times the emission pattern towards the camera along the mirrored
// axis (over the IRED's own), and it follows the current.
TEST(LabScene, ReflectionFluxIsReflectanceTimesPatternAndFollowsTheCurrent) {
  RigPhysics p;
  p.scene.reflection = {20.0, 0.2};
  const Scene scene(p);
  const LabScene lab(scene);
  for (const PoseState& pose : {Pose(2000, 0, 0), Pose(1500, 10, 20), Pose(2500, 0, -25)}) {
    const double i0 = scene.OnAxisIntensityMwSr(pose.bias_ma, 0.0);
    const DiscSource ired = scene.EmitterDisc(pose, i0);
    const DiscSource mirror = *lab.ReflectionDisc(pose, i0);
    // Pattern over the square of the distance, times the cosine of the field angle (vignetting's
    // cos^4 on an image area that grows as 1 / cos^3).
    auto expected_flux = [&](const DiscSource& d) {
      const double r = std::hypot(d.center_mm[0], d.center_mm[1], d.center_mm[2]);
      const double cos_a = -(d.axis[0] * d.center_mm[0] + d.axis[1] * d.center_mm[1] +
                             d.axis[2] * d.center_mm[2]) / r;
      return scene.Pattern(std::acos(cos_a)) / (r * r) * d.center_mm[2] / r;
    };
    const double ratio =
        Sum(scene.RenderDisc(mirror, 0.01)) / Sum(scene.RenderSignal(pose, i0, 0.01));
    EXPECT_NEAR(ratio / (0.2 * expected_flux(mirror) / expected_flux(ired)), 1.0, 0.01)
        << pose.pan_deg << " " << pose.tilt_deg;
  }
  // Twice the light above threshold, twice the reflection; none when the IRED is off.
  const Renderer renderer(p);
  const double low = Sum(renderer.Signal(StaticConditions(2000, 0, 0, 150, 0.01)));
  const double high = Sum(renderer.Signal(StaticConditions(2000, 0, 0, 250, 0.01)));
  EXPECT_NEAR(high / low, scene.OnAxisIntensityMwSr(250, 0) / scene.OnAxisIntensityMwSr(150, 0),
              1e-4);
  EXPECT_EQ(Sum(renderer.Signal(StaticConditions(2000, 0, 0, 0, 0.01))), 0.0);
}

// The second source sits where its position projects, and its light does not depend on the
// IRED's current; I = 0.5 I0 (D2 / D)^2 gives about half the IRED's peak (the recipe of
// docs/virtual-rig.md).
TEST(LabScene, SecondSourceIsFixedAndIndependentOfTheCurrent) {
  RigPhysics p;
  const Scene plain(p);
  const double i0 = plain.OnAxisIntensityMwSr(300, 0.0);
  p.scene.second_source.position_mm = {10.0, -6.0, 2000.0};
  p.scene.second_source.diameter_mm = 5.0;
  p.scene.second_source.intensity_mw_sr = 0.5 * i0 * 0.25;
  const Renderer renderer(p);
  const Scene& scene = renderer.scene();
  const SignalWindow second = scene.RenderDisc(*renderer.lab().SecondSourceDisc(), 0.01);
  const cv::Point2d at = Centroid(second);
  EXPECT_NEAR(at.x, 640.0 + 10.0 * PixelsPerMm(p) / 2000.0, 0.05);
  EXPECT_NEAR(at.y, 512.0 - 6.0 * PixelsPerMm(p) / 2000.0, 0.05);
  // With the IRED off, the signal is the second source's alone; at any current its pixels (15 px
  // from the IRED's, beyond the IRED's blur) are the same.
  const SignalWindow dark = renderer.Signal(StaticConditions(2000, 0, 0, 0, 0.01));
  ASSERT_EQ(dark.rect & second.rect, second.rect);
  EXPECT_EQ(cv::norm(dark.electrons(second.rect - dark.rect.tl()), second.electrons, cv::NORM_INF),
            0.0);
  EXPECT_DOUBLE_EQ(Sum(dark), Sum(second));
  const SignalWindow lit = renderer.Signal(StaticConditions(2000, 0, 0, 300, 0.01));
  const cv::Rect far = second.rect & cv::Rect(650, 0, 100, 1024);
  ASSERT_FALSE(far.empty());
  EXPECT_LT(cv::norm(lit.electrons(far - lit.rect.tl()), second.electrons(far - second.rect.tl()),
                     cv::NORM_INF),
            1e-3 * cv::norm(second.electrons, cv::NORM_INF));
  double ired_peak = 0.0, second_peak = 0.0;
  cv::minMaxLoc(plain.RenderSignal(Pose(2000, 0, 0), i0, 0.01).electrons, nullptr, &ired_peak);
  cv::minMaxLoc(second.electrons, nullptr, &second_peak);
  EXPECT_NEAR(second_peak / ired_peak, 0.5, 0.03);
}

// Ambient light: the frame's mean over the dark IRED is (dark + ambient) x exposure, the same
// at any current, with the shot noise of light; the gradient spans the sensor.
TEST(LabScene, AmbientIsProportionalToExposureAndIndependentOfTheCurrent) {
  RigPhysics p;
  p.scene.ambient.center_e_per_s = 6000.0;  // 2% of the full well at 35 ms
  p.scene.ambient.gradient_x_percent = 50.0;
  const Renderer renderer(p);
  const SensorOptions& s = p.sensor;
  // Rows 100-131 over the full width, far from the IRED.
  auto mean_e = [&](double bias_ma, double exposure_s, int x0, int width, double* var_e) {
    cv::Mat out(32, width, CV_16UC1);
    renderer.Render(StaticConditions(2000, 0, 0, bias_ma, exposure_s), 9, PixelFormat::kMono12,
                    cv::Point(x0, 100), out);
    cv::Scalar mean, sd;
    cv::meanStdDev(out, mean, sd);
    if (var_e != nullptr) *var_e = std::pow(sd[0] / s.system_gain_dn_per_e, 2);
    return (mean[0] - s.black_level_dn) / s.system_gain_dn_per_e;
  };
  for (double exposure_s : {0.010, 0.035}) {
    double var_e = 0.0;
    const double e = mean_e(0, exposure_s, 576, 128, &var_e);  // centred: the centre's rate
    const double expected = (6000.0 + s.dark_current_e_per_s) * exposure_s;
    EXPECT_NEAR(e / expected, 1.0, 0.02) << exposure_s;
    EXPECT_NEAR(var_e / (expected + s.read_noise_e * s.read_noise_e + 1.0 / 12 / 0.39 / 0.39), 1.0,
                0.1);
    EXPECT_NEAR(mean_e(500, exposure_s, 576, 128, nullptr) / e, 1.0, 0.01);
  }
  const double left = mean_e(0, 0.035, 0, 64, nullptr), right = mean_e(0, 0.035, 1216, 64, nullptr);
  const double span = (1216.0 + 32.0 - 32.0) / 1280.0;  // the two strips' centres apart
  EXPECT_NEAR((right - left) / (6000.0 * 0.035), 0.5 * span, 0.03);
  EXPECT_NEAR(renderer.lab().AmbientRateEPerS(639, 511), 6000.0 * (1.0 - 0.5 * 0.5 / 1280), 1e-6);
}

// The occluder: the disc's flux falls by the covered fraction (within 1%), the image's centre
// moves away from the covered side as a circular segment's centroid says, and a vanishing cut
// gives the uncut image.
TEST(LabScene, OccluderRemovesTheCoveredFractionOfTheFlux) {
  const Scene plain{RigPhysics{}};
  for (const PoseState& pose : {Pose(2000, 0, 0), Pose(1500, 30, 10), Pose(3000, -20, -25)}) {
    for (double fraction : {0.05, 0.15, 0.5}) {
      for (double angle : {0.0, 90.0, 200.0}) {
        RigPhysics p;
        p.scene.occluder = {fraction, angle};
        const Scene scene(p);
        const double i0 = scene.OnAxisIntensityMwSr(pose.bias_ma, 0.0);
        const double full = Sum(plain.RenderSignal(pose, i0, 0.01));
        const double cut = Sum(scene.RenderSignal(pose, i0, 0.01));
        EXPECT_NEAR((full - cut) / full / fraction, 1.0, 0.01)
            << pose.pan_deg << " " << fraction << " " << angle;
      }
    }
  }
}

TEST(LabScene, OccludedImageMovesLikeTheSegmentsCentroidAndAVanishingCutIsTheDisc) {
  const PoseState pose = Pose(2000, 0, 0);
  const Scene plain{RigPhysics{}};
  const double i0 = plain.OnAxisIntensityMwSr(pose.bias_ma, 0.0);
  const SignalWindow full = plain.RenderSignal(pose, i0, 0.01);
  const double radius_px = 0.5 * plain.Project(pose).major_px;
  for (double angle : {90.0, 270.0, 0.0}) {
    RigPhysics p;
    p.scene.occluder = {0.15, angle};
    const Scene scene(p);
    // The covered segment (chord at t R): area R^2 (acos t - t sqrt(1 - t^2)), centroid
    // 2 R (1 - t^2)^1.5 / (3 (acos t - t sqrt(1 - t^2))) from the centre; the rest moves away.
    double lo = -1, hi = 1;
    for (int i = 0; i < 100; ++i) {
      const double t = 0.5 * (lo + hi);
      ((std::acos(t) - t * std::sqrt(1 - t * t)) / kPi > 0.15 ? lo : hi) = t;
    }
    const double t = lo, a = std::acos(t) - t * std::sqrt(1 - t * t);
    const double segment_px = 2.0 * radius_px * std::pow(1 - t * t, 1.5) / (3.0 * a);
    const double shift_px = -0.15 / 0.85 * segment_px;
    const cv::Point2d moved = Centroid(scene.RenderSignal(pose, i0, 0.01)) - Centroid(full);
    EXPECT_NEAR(moved.x, shift_px * std::cos(angle * kDeg), 0.02) << angle;
    EXPECT_NEAR(moved.y, shift_px * std::sin(angle * kDeg), 0.02) << angle;
  }
  RigPhysics p;
  p.scene.occluder = {1e-9, 45.0};
  const SignalWindow barely = Scene(p).RenderSignal(pose, i0, 0.01);
  ASSERT_EQ(barely.rect, full.rect);
  EXPECT_LT(cv::norm(barely.electrons, full.electrons, cv::NORM_INF),
            1e-4 * cv::norm(full.electrons, cv::NORM_INF));
}

// docs/virtual-rig.md "A lab's scene": every example snippet loads and turns a fault on.
TEST(LabScene, DocumentedExamplesLoad) {
  std::ifstream in(std::string(IRDIST_SOURCE_DIR) + "/docs/virtual-rig.md");
  std::stringstream text;
  text << in.rdbuf();
  const std::string doc = text.str();
  size_t at = doc.find("## A lab's scene");
  const size_t end = doc.find("\n## ", at + 1);
  ASSERT_NE(at, std::string::npos);
  int examples = 0;
  for (size_t open = doc.find("```yaml\n", at); open < end; open = doc.find("```yaml\n", at)) {
    const size_t close = doc.find("```", open + 8);
    const std::string path = std::string(IRDIST_BINARY_DIR) + "/sim_lab_scene_example_" +
                             std::to_string(examples++) + ".yaml";
    std::ofstream(path) << doc.substr(open + 8, close - open - 8);
    const RigPhysics p = LoadRigPhysics(path);
    const LabSceneOptions& s = p.scene;
    EXPECT_TRUE(p.sensor.defects.Count() > 0 || s.ambient.On() || s.reflection.On() ||
                s.second_source.On() || s.occluder.On())
        << path;
    at = close + 3;
  }
  EXPECT_EQ(examples, 6);
}

}  // namespace
}  // namespace irdist::sim
