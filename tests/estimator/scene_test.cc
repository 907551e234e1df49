#include "estimator/scene.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "estimator/blob_fit.h"
#include "estimator/features.h"
#include "tests/estimator/scene_render.h"

namespace irdist {
namespace {

using testing::NormalField;
using testing::RenderScene;
using testing::SceneDisc;
using testing::SensorFrame;

constexpr int kSide = 128;

struct Measured {
  Features f;
  SceneReport r;
  cv::Mat cleaned;
};

// What FrameFeatures does without a model: the scene pass, then the features of its frame.
Measured Measure(const cv::Mat& frame, const SceneContext& context = {}) {
  const SceneFrame s = CleanScene(frame, 12, SceneOptions(), context);
  return {ComputeFeatures(s.image, 12, FeatureOptions()), s.report, s.image};
}

// A disc as a bench sees one at 1.5-3 m: radius 6-10 px, tilted up to 30 deg (axis ratio down to
// 0.87), blur sigma 0.5-1.0 px, plateau 270-3500 DN (a bracket's reference exposures are dim).
struct RandomScene {
  SceneDisc disc;
  double blur_px = 0.7;
  double background_e = 50.0;
};
RandomScene Random(std::mt19937_64* rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  RandomScene s;
  s.disc.a = 6.0 + 4.0 * u(*rng);
  s.disc.b = s.disc.a * (0.87 + 0.13 * u(*rng));
  s.disc.angle_deg = 180.0 * u(*rng);
  s.disc.cx = kSide / 2 + 6.0 * (u(*rng) - 0.5);
  s.disc.cy = kSide / 2 + 6.0 * (u(*rng) - 0.5);
  s.disc.amplitude_e = 700.0 * std::pow(9000.0 / 700.0, u(*rng));  // short and long exposures
  s.blur_px = 0.5 + 0.5 * u(*rng);
  s.background_e = 20.0 + 180.0 * u(*rng);
  return s;
}

double Rel(double a, double b) { return std::abs(a - b) / std::max(std::abs(b), 1e-300); }

bool Contains(const std::vector<cv::Point>& points, cv::Point p) {
  return std::find(points.begin(), points.end(), p) != points.end();
}

TEST(SceneOptions, DefaultsAreValid) {
  std::string why;
  EXPECT_TRUE(SceneOptions().IsValid(&why)) << why;
  SceneOptions bad;
  bad.defect_sigmas = 1.0;
  EXPECT_FALSE(bad.IsValid(&why));
  EXPECT_NE(why.find("defect_sigmas"), std::string::npos);
  EXPECT_TRUE(FeatureOptions().scene.enabled);
}

TEST(Scene, OffLeavesTheFrameAlone) {
  std::mt19937_64 rng(1);
  const RandomScene s = Random(&rng);
  const cv::Mat frame =
      SensorFrame(RenderScene(kSide, s.background_e, {s.disc}, s.blur_px), NormalField(kSide, &rng));
  SceneOptions off;
  off.enabled = false;
  const SceneFrame out = CleanScene(frame, 12, off);
  EXPECT_FALSE(out.report.assessed);
  EXPECT_EQ(out.image.data, frame.data);
}

// Hot pixels at the blob's centre, on its edge and in the background, pairs, stuck pixels at 0
// and mid-scale: every one caught and replaced; the features equal the clean frame's. (Defects are
// looked for in the feature window and around every blob: a dark pixel elsewhere touches nothing.)
TEST(SceneDefects, HotAndStuckPixelsAreCaughtAndReplaced) {
  std::mt19937_64 rng(7);
  SceneDisc d;
  d.cx = 64.3, d.cy = 63.7, d.a = 8.0, d.b = 7.6, d.angle_deg = 20.0, d.amplitude_e = 7000.0;
  const cv::Mat clean = SensorFrame(RenderScene(kSide, 50.0, {d}, 0.6), NormalField(kSide, &rng));
  cv::Mat bad = clean.clone();
  const std::vector<std::pair<cv::Point, int>> defects = {
      {{64, 64}, 3276},  {{72, 64}, 2457},  {{56, 62}, 3900},  {{30, 30}, 3700},
      {{62, 66}, 0},     {{100, 40}, 2048}, {{20, 100}, 2900}, {{21, 100}, 2900},
      {{66, 62}, 4095},  {{66, 63}, 4095},  {{64, 72}, 2600},  {{36, 92}, 0}};
  for (const auto& [p, g] : defects) bad.at<uint16_t>(p) = static_cast<uint16_t>(g);
  const Measured m = Measure(bad), c = Measure(clean);
  for (const auto& [p, g] : defects) {
    EXPECT_TRUE(Contains(m.r.defect_px, p)) << p << " at " << g;
  }
  EXPECT_TRUE(c.r.defect_px.empty()) << c.r.BriefReport();
  EXPECT_GE(m.r.defect_pixels_near_blob, 7) << m.r.BriefReport();
  EXPECT_FALSE(m.r.second_source || m.r.occluded) << m.r.BriefReport();
  EXPECT_EQ(m.r.other_blobs, 0);
  const Features& a = m.f;
  const Features& b = c.f;
  std::printf("defect frame vs clean: e_rel %.2e f00 %.2e sigma %.2e major %.2e minor %.2e\n",
              Rel(a.e_rel, b.e_rel), Rel(a.f00, b.f00), Rel(a.sigma, b.sigma),
              Rel(a.moment_major_var_px2, b.moment_major_var_px2),
              Rel(a.moment_minor_var_px2, b.moment_minor_var_px2));
  EXPECT_LT(Rel(a.e_rel, b.e_rel), 5e-4);
  EXPECT_LT(Rel(a.f00, b.f00), 5e-4);
  EXPECT_LT(Rel(a.sigma, b.sigma), 5e-4);
  EXPECT_LT(Rel(a.moment_major_var_px2, b.moment_major_var_px2), 2e-3);
  EXPECT_LT(Rel(a.moment_minor_var_px2, b.moment_minor_var_px2), 2e-3);
  // The blob fit on the cleaned frame (the calibrated blur given): the same disc.
  const double blur_var = 0.36 + 1.0 / 12.0;
  const BlobFitResult fa = FitBlob(m.cleaned, 12, a, blur_var), fb = FitBlob(c.cleaned, 12, b, blur_var);
  ASSERT_TRUE(fa.ok && fb.ok);
  std::printf("blob fit: major %.2e minor %.2e\n", Rel(fa.major_var_px2, fb.major_var_px2),
              Rel(fa.minor_var_px2, fb.minor_var_px2));
  EXPECT_LT(Rel(fa.major_var_px2, fb.major_var_px2), 2e-3);
  EXPECT_LT(Rel(fa.minor_var_px2, fb.minor_var_px2), 2e-3);
}

// One hot pixel (60-100% of full scale) at a random place: on the disc's edge, at its centre, in
// the background; caught on nearly every frame.
TEST(SceneDefects, DetectionRateOfHotPixels) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const char* where[3] = {"centre", "edge", "background"};
  for (int place = 0; place < 3; ++place) {
    int caught = 0, n = 0, worst_miss = 0;
    for (int i = 0; i < 60; ++i) {
      const RandomScene s = Random(&rng);
      cv::Mat frame = SensorFrame(RenderScene(kSide, s.background_e, {s.disc}, s.blur_px),
                                  NormalField(kSide, &rng));
      const double phi = 2.0 * testing::kScenePi * u(rng);
      const double r = place == 0 ? 2.0 * u(rng) : place == 1 ? s.disc.b + 0.5 * (s.disc.a - s.disc.b) : 25.0;
      const cv::Point p(static_cast<int>(std::lround(s.disc.cx + r * std::cos(phi))),
                        static_cast<int>(std::lround(s.disc.cy + r * std::sin(phi))));
      const int before = frame.at<uint16_t>(p);
      const int hot = static_cast<int>(4095.0 * (0.6 + 0.4 * u(rng)));
      frame.at<uint16_t>(p) = static_cast<uint16_t>(hot);
      const Measured m = Measure(frame);
      ++n;
      if (Contains(m.r.defect_px, p)) {
        ++caught;
      } else {
        worst_miss = std::max(worst_miss, std::abs(hot - before));
      }
    }
    std::printf("hot pixel at the %s: caught %d / %d (the worst miss %d DN from the truth)\n",
                where[place], caught, n, worst_miss);
    EXPECT_GE(caught, n * 9 / 10) << where[place];
    // What is missed sits near the pixel's own level (a hot pixel about as bright as a plateau).
    EXPECT_LT(worst_miss, 0.1 * 4095) << where[place];
  }
}

// A known defect map's pixels are replaced even where they look like their neighbours.
TEST(SceneDefects, KnownMapIsAlwaysMasked) {
  std::mt19937_64 rng(3);
  const RandomScene s = Random(&rng);
  const cv::Mat frame =
      SensorFrame(RenderScene(kSide, s.background_e, {s.disc}, s.blur_px), NormalField(kSide, &rng));
  DefectMap map;
  map.sensor_px = {{110, 210}, {5, 5}};  // sensor coordinates; the frame's ROI starts at (100, 200)
  SceneContext context;
  context.known_defects = &map;
  context.roi_origin_known = true;
  context.roi_origin = cv::Point(100, 200);
  const Measured m = Measure(frame, context);
  EXPECT_TRUE(Contains(m.r.defect_px, cv::Point(10, 10)));
  EXPECT_EQ(m.r.defect_px.size(), 1u) << m.r.BriefReport();
  // The options' map (a calibration's, found in this ROI): the frame is that ROI.
  SceneOptions options;
  options.defect_map.sensor_px = {{103, 207}};
  options.defect_map.roi = cv::Rect(100, 200, kSide, kSide);
  const SceneFrame out = CleanScene(frame, 12, options);
  EXPECT_EQ(out.report.defect_px, std::vector<cv::Point>{cv::Point(3, 7)});
}

// Clean noisy frames (sizes, tilts, blurs, levels): the detectors' false alarms, and the features
// unchanged by the pass.
TEST(Scene, FalseAlarmsOnCleanFrames) {
  std::mt19937_64 rng(2026);
  const int frames = 300;
  long pixels = 0, defects = 0;
  int other = 0, second = 0, occluded = 0;
  double change = 0.0, worst_edge = 0.0;
  for (int i = 0; i < frames; ++i) {
    const RandomScene s = Random(&rng);
    const cv::Mat frame = SensorFrame(RenderScene(kSide, s.background_e, {s.disc}, s.blur_px),
                                      NormalField(kSide, &rng));
    const Measured m = Measure(frame);
    const Features raw = ComputeFeatures(frame, 12, FeatureOptions());
    pixels += frame.total();
    defects += static_cast<long>(m.r.defect_px.size());
    other += m.r.other_blobs > 0;
    second += m.r.second_source;
    occluded += m.r.occluded;
    worst_edge = std::max(worst_edge, m.r.occluded_edge_fraction);
    change += (Rel(m.f.e_rel, raw.e_rel) + Rel(m.f.f00, raw.f00) + Rel(m.f.sigma, raw.sigma) +
               Rel(m.f.moment_major_var_px2, raw.moment_major_var_px2)) / 4.0;
  }
  const double rate = static_cast<double>(defects) / pixels;
  std::printf("clean frames: %d, defect false alarms %ld (%.2e per pixel), other blobs %d, second "
              "source %d, occluded %d (largest departed edge fraction %.3f), mean feature change "
              "%.2e\n",
              frames, defects, rate, other, second, occluded, worst_edge, change / frames);
  EXPECT_LT(rate, 1e-4);
  EXPECT_EQ(other, 0);
  EXPECT_EQ(second, 0);
  EXPECT_LE(occluded, frames / 100);
  EXPECT_LT(change / frames, 1e-4);
}

// A second blob (a reflection at 20%, a second LED at 50%) at 8, 15, 25, 40 px (edge to edge):
// masked, the features those of the frame without it; nearer, named a second source.
TEST(SceneSegments, SecondBlobIsMaskedOrNamed) {
  std::mt19937_64 rng(5);
  for (double brightness : {0.2, 0.5}) {
    for (double gap : {8.0, 15.0, 25.0, 40.0, 2.0, -1.0}) {
      SceneDisc d;
      d.cx = 58.4, d.cy = 60.6, d.a = 8.0, d.b = 7.5, d.angle_deg = 35.0, d.amplitude_e = 7000.0;
      SceneDisc other = d;
      other.amplitude_e = brightness * d.amplitude_e;
      other.a = other.b = 6.0;
      const double phi = 0.6;
      other.cx = d.cx + (d.a + other.a + gap) * std::cos(phi);
      other.cy = d.cy + (d.a + other.a + gap) * std::sin(phi);
      const cv::Mat1d z = NormalField(kSide, &rng);
      const cv::Mat clean = SensorFrame(RenderScene(kSide, 50.0, {d}, 0.7), z);
      const cv::Mat two = SensorFrame(RenderScene(kSide, 50.0, {d, other}, 0.7), z);
      const Measured m = Measure(two), c = Measure(clean);
      std::printf("brightness %.1f gap %5.1f: %s; e_rel %.2e f00 %.2e sigma %.2e major %.2e\n",
                  brightness, gap, m.r.BriefReport().c_str(), Rel(m.f.e_rel, c.f.e_rel),
                  Rel(m.f.f00, c.f.f00), Rel(m.f.sigma, c.f.sigma),
                  Rel(m.f.moment_major_var_px2, c.f.moment_major_var_px2));
      if (gap >= 8.0) {
        EXPECT_NEAR(m.r.blob_center_px.x, d.cx, 0.5);
        EXPECT_FALSE(m.r.second_source) << gap;
        // Beyond 40 px the other blob lies outside the 64 px window (not counted, still masked).
        EXPECT_EQ(m.r.other_blobs, gap < 40.0 ? 1 : 0) << gap;
        EXPECT_LT(Rel(m.f.e_rel, c.f.e_rel), 5e-4) << gap;
        EXPECT_LT(Rel(m.f.f00, c.f.f00), 5e-4) << gap;
        EXPECT_LT(Rel(m.f.sigma, c.f.sigma), 5e-4) << gap;
        EXPECT_LT(Rel(m.f.moment_major_var_px2, c.f.moment_major_var_px2), 5e-4) << gap;
      } else if (brightness < 0.5 || gap > 0.0) {
        EXPECT_TRUE(m.r.second_source) << gap;
      } else {
        // A blob as bright as the disc's half maximum overlapping it: its edge is no ellipse.
        EXPECT_TRUE(m.r.second_source || m.r.occluded) << gap;
      }
    }
  }
}

// The window's blob is the IRED: not a brighter second LED when the expected centre is given, not
// a cluster of hot pixels.
TEST(SceneSegments, PicksTheIred) {
  std::mt19937_64 rng(9);
  SceneDisc d;
  d.cx = 40.2, d.cy = 44.7, d.a = d.b = 7.0, d.amplitude_e = 4000.0;
  SceneDisc led = d;
  led.cx = 95.0, led.cy = 90.0, led.a = led.b = 9.0, led.amplitude_e = 8000.0;
  const cv::Mat frame = SensorFrame(RenderScene(kSide, 50.0, {d, led}, 0.7), NormalField(kSide, &rng));
  SceneContext context;
  context.has_expected_center = true;
  context.expected_center_px = cv::Point2d(42.0, 43.0);
  const Measured m = Measure(frame, context);
  EXPECT_NEAR(m.f.centroid_px.x, d.cx, 0.2) << m.r.BriefReport();
  EXPECT_NEAR(m.f.centroid_px.y, d.cy, 0.2);
  // Without it, the most flux: the LED.
  EXPECT_NEAR(Measure(frame).f.centroid_px.x, led.cx, 0.2);
}

// A straight occluder across 5%, 15%, 30% of the disc, on noisy frames at 1.5-3 m (radius 6-10
// px, tilts up to 30 deg, blur 0.5-1 px): named occluded.
TEST(SceneOcclusion, CutDiscsAreNamed) {
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (double cut : {0.05, 0.15, 0.30}) {
    int named = 0;
    const int n = 100;
    std::vector<double> fractions;
    for (int i = 0; i < n; ++i) {
      RandomScene s = Random(&rng);
      s.disc.cut = cut;
      s.disc.cut_angle_deg = 360.0 * u(rng);
      const Measured m = Measure(SensorFrame(RenderScene(kSide, s.background_e, {s.disc}, s.blur_px),
                                             NormalField(kSide, &rng)));
      named += m.r.occluded;
      fractions.push_back(m.r.occluded_edge_fraction);
    }
    std::sort(fractions.begin(), fractions.end());
    std::printf("cut %.2f: named occluded on %d / %d frames (departed edge fraction: 5th percentile "
                "%.3f, median %.3f)\n",
                cut, named, n, fractions[n / 20], fractions[n / 2]);
    if (cut >= 0.15) {
      EXPECT_GE(named, n * 95 / 100) << cut;
    }
  }
}

// A cable across the disc (a dark band 1.5-2.5 px wide, within 3 px of its centre): occluded. Its
// shadow is a line (no defect); where it crosses the disc's edge the corners are sharper than any
// blurred convex edge, and the defect test takes a few of their pixels (the frame is named anyway).
TEST(SceneOcclusion, CableAcrossTheDiscIsNamedNotErased) {
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int named = 0, defects = 0;
  const int n = 60;
  for (int i = 0; i < n; ++i) {
    RandomScene s = Random(&rng);
    s.disc.band_px = 1.5 + u(rng);
    s.disc.band_offset_px = 6.0 * (u(rng) - 0.5);
    s.disc.cut_angle_deg = 360.0 * u(rng);
    const Measured m = Measure(SensorFrame(RenderScene(kSide, s.background_e, {s.disc}, s.blur_px),
                                           NormalField(kSide, &rng)));
    named += m.r.occluded;
    defects += m.r.defect_pixels;
  }
  std::printf("cable across the disc: named occluded on %d / %d frames, %d defect pixels\n", named,
              n, defects);
  EXPECT_GE(named, n * 95 / 100);
  EXPECT_LE(defects, 10 * n);
}

}  // namespace
}  // namespace irdist
