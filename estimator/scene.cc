// The scene pass (estimator/scene.h): its options, its report, and the pass in order.
#include "estimator/scene.h"

#include <cmath>
#include <sstream>

#include <opencv2/imgproc.hpp>

#include "base/check.h"
#include "estimator/scene_internal.h"

namespace irdist {

bool SceneOptions::IsValid(std::string* why) const {
  auto fail = [why](const char* message) {
    if (why != nullptr) *why = message;
    return false;
  };
  if (!(defect_sigmas >= 3.0)) return fail("scene.defect_sigmas must be >= 3");
  if (!(defect_edge_allowance >= 0.0 && defect_edge_allowance < 1.0))
    return fail("scene.defect_edge_allowance must be in [0, 1)");
  if (!(fallback_shot_gain_dn >= 0.0)) return fail("scene.fallback_shot_gain_dn must be >= 0");
  if (!(segment_sigmas > 0.0)) return fail("scene.segment_sigmas must be > 0");
  if (!(segment_peak_fraction >= 0.0 && segment_peak_fraction < 0.5))
    return fail("scene.segment_peak_fraction must be in [0, 0.5)");
  if (min_blob_area_px < 1) return fail("scene.min_blob_area_px must be >= 1");
  if (!(halo_reach_px >= 0.0 && halo_reach_px <= 32.0))
    return fail("scene.halo_reach_px must be in [0, 32]");
  if (!(merged_reach_px > 0.0)) return fail("scene.merged_reach_px must be > 0");
  if (occlusion_rays < 16) return fail("scene.occlusion_rays must be >= 16");
  if (!(occlusion_residual_px > 0.0)) return fail("scene.occlusion_residual_px must be > 0");
  if (!(occluded_min_fraction > 0.0 && occluded_min_fraction <= 1.0))
    return fail("scene.occluded_min_fraction must be in (0, 1]");
  if (occlusion_min_run < 1) return fail("scene.occlusion_min_run must be >= 1");
  if (defect_map.roi.width < 0 || defect_map.roi.height < 0)
    return fail("scene.defect_map.roi must have a non-negative size");
  if (!(occlusion_min_radius_px >= 1.0)) return fail("scene.occlusion_min_radius_px must be >= 1");
  return true;
}

std::string SceneReport::BriefReport() const {
  if (!assessed) return "scene: not assessed";
  std::ostringstream out;
  out << "scene: " << defect_pixels << " defect pixels (" << defect_pixels_near_blob
      << " near the blob), " << other_blobs << " other blobs";
  if (std::isfinite(second_source_gap_px)) out << " (nearest " << second_source_gap_px << " px)";
  if (second_source) out << ", SECOND SOURCE";
  if (occluded) out << ", OCCLUDED (" << occluded_edge_fraction << " of the edge)";
  out << ", ambient " << ambient_level << ", read noise " << read_noise_dn << " DN";
  return out.str();
}

namespace {

cv::Rect WindowAround(cv::Point2d c, int side) {
  return cv::Rect(static_cast<int>(std::lround(c.x - 0.5 * (side - 1))),
                  static_cast<int>(std::lround(c.y - 0.5 * (side - 1))), side, side);
}

// Where the defects are looked for: the IRED's feature window (and its blob, grown), first, and
// every other component's box grown by 3 px (a hot pixel far out is a component of its own);
// the whole frame when there is no IRED. A 256 x 256 ROI's median and tests run on a 16th of it.
std::vector<cv::Rect> DefectRegions(const scene::Segments& segments, const SceneContext& context,
                                    cv::Size size) {
  const cv::Rect frame(cv::Point(0, 0), size);
  if (segments.ired < 0) return {frame};
  const scene::Blob& ired = segments.blobs[static_cast<std::size_t>(segments.ired)];
  const cv::Rect grown_blob = ired.rect - cv::Point(8, 8) + cv::Size(16, 16);
  std::vector<cv::Rect> regions = {
      (WindowAround(ired.centroid, context.window_side_px) | grown_blob) & frame};
  for (std::size_t i = 0; i < segments.blobs.size(); ++i) {
    if (static_cast<int>(i) == segments.ired) continue;
    regions.push_back((segments.blobs[i].rect - cv::Point(3, 3) + cv::Size(6, 6)) & frame);
  }
  return regions;
}

// The defect pixels of each region (255 in *defects, frame-sized); the shot noise's gain
// measured first, on the first region (the IRED's).
void FindDefects(const cv::Mat& image, int bit_depth, const std::vector<cv::Rect>& regions,
                 const SceneOptions& options, scene::NoiseModel* noise, cv::Mat* defects) {
  const cv::Rect frame(0, 0, image.cols, image.rows);
  for (std::size_t i = 0; i < regions.size(); ++i) {
    const cv::Rect r = (regions[i] - cv::Point(1, 1) + cv::Size(2, 2)) & frame;  // + neighbours
    if (r.width < 3 || r.height < 3) continue;
    cv::Mat median3;
    cv::medianBlur(image(r), median3, 3);
    if (i == 0) {
      scene::MeasureShotGain(image(r), median3, bit_depth, options.fallback_shot_gain_dn, noise);
    }
    if (!options.detect_defects) break;
    cv::Mat local = (*defects)(r);
    cv::bitwise_or(local, scene::DetectDefects(image(r), median3, *noise, options), local);
  }
}

// The known maps' pixels (the options' and the context's) set in *defects.
void AddKnownMaps(const SceneOptions& options, const SceneContext& context, cv::Mat* defects) {
  for (const DefectMap* map : {&options.defect_map, context.known_defects}) {
    if (map == nullptr || map->empty()) continue;
    if (context.roi_origin_known) {
      scene::AddKnownDefects(*map, context.roi_origin, defects);
    } else if (map->roi.empty() || map->roi.size() == defects->size()) {
      scene::AddKnownDefects(*map, map->roi.tl(), defects);  // the frame is the map's ROI
    }
  }
}

// The defects inside the feature window and, of them, those within the blob fit's reach (the
// IRED's pixels grown by the halo and the fit's 2 px margin).
void CountDefects(const scene::Segments& segments, const SceneOptions& options,
                  const SceneContext& context, cv::Size frame, SceneReport* report) {
  if (segments.ired < 0) {
    report->defect_pixels = static_cast<int>(report->defect_px.size());
    return;
  }
  const scene::Blob& ired = segments.blobs[static_cast<std::size_t>(segments.ired)];
  const cv::Rect window = WindowAround(ired.centroid, context.window_side_px);
  const scene::LocalMask near = scene::GrownMask(segments, ired, options.halo_reach_px + 2.0, frame);
  for (const cv::Point& p : report->defect_px) {
    if (!window.contains(p)) continue;
    ++report->defect_pixels;
    if (near.Has(p)) ++report->defect_pixels_near_blob;
  }
}

}  // namespace

SceneFrame CleanScene(const cv::Mat& image, int bit_depth, const SceneOptions& options,
                      const SceneContext& context) {
  std::string why;
  IRDIST_CHECK(options.IsValid(&why), why);
  IRDIST_CHECK(image.type() == CV_16UC1, "CleanScene needs a CV_16UC1 image, got type ",
               image.type());
  IRDIST_CHECK(bit_depth >= 8 && bit_depth <= 16, "bit_depth must be in [8,16], got ", bit_depth);
  SceneFrame out;
  out.image = image;
  if (!options.enabled || image.rows < 3 || image.cols < 3) return out;
  SceneReport& report = out.report;
  report.assessed = true;
  scene::NoiseModel noise = scene::MeasureBackgroundNoise(image, bit_depth);
  // The components of the raw frame say where to look for defects; found, they are replaced and
  // leave their components (a hot pixel alone is then no component).
  scene::Segments segments;
  if (options.segment) segments = scene::Segment(image, noise, options, context);
  cv::Mat defects = cv::Mat::zeros(image.size(), CV_8U);
  FindDefects(image, bit_depth, DefectRegions(segments, context, image.size()), options, &noise,
              &defects);
  AddKnownMaps(options, context, &defects);
  report.ambient_level = noise.background / ((1 << bit_depth) - 1);
  report.read_noise_dn = noise.read_sd;
  report.shot_gain_dn = noise.shot_gain;
  if (cv::countNonZero(defects) > 0) {
    out.image = image.clone();
    scene::ReplaceDefects(defects, &out.image, &report.defect_px);
    scene::ForgetDefects(out.image, report.defect_px, options, context, &segments);
  }
  if (segments.ired >= 0) {
    report.blob_center_px = segments.blobs[static_cast<std::size_t>(segments.ired)].centroid;
    if (segments.blobs.size() > 1) {
      if (out.image.data == image.data) out.image = image.clone();
      scene::MaskOtherBlobs(segments, options, context, &out.image, &report);
    }
    scene::AssessShape(out.image, segments, noise, options, &report);
  }
  CountDefects(segments, options, context, image.size(), &report);
  return out;
}

}  // namespace irdist
